"""How much of the success target can any policy reach? Per-context search on the agents' test contexts.

A learned policy maps each context to one action; its success rate on the test contexts cannot exceed the
fraction of test contexts where *some* action succeeds. This benchmark estimates that fraction by searching
each test context on its own (an oracle that knows the context and may spend episodes in it):

1. ``grid``: the amplitude factors of the two table axes over a 5 x 5 grid in ``[-0.3, 0.9]`` (action units),
   with ``approach = +1`` where the context has a cup (the lift that clears it) and 0 elsewhere;
2. ``cmaes``: where the grid finds no success, CMA-ES over the whole action (every DMP weight, the initial
   conditions, the amplitudes and the approach) on that one context, started at the grid's best action,
   maximising ``coverage + success`` (not the reward: the question is whether success is reachable at all).

A context where neither finds a success is counted as unreached. This is an estimate from a finite search,
not a proof: it bounds what the agents' ``learn one policy for all contexts`` can be expected to reach.

    python benchmarks/bench_feasibility.py --save     # 20 test contexts, 300 CMA-ES episodes each
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
from concurrent.futures import ProcessPoolExecutor

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import cma
import gymnasium as gym
import numpy as np
import rdmp_gym.envs  # noqa: F401  (registers the env)
from output import add_save_argument, results_dir
from rdmp_gym.agents.protocol import final_test_seeds, interval
from rdmp_gym.agents.tasks import WIPE_ID, run_episode
from rdmp_gym.envs.tasks.wiping.context import CONTEXT_FIELDS

GRID = (-0.3, 0.0, 0.3, 0.6, 0.9)


def _parse() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--test-contexts", type=int, default=20, help="the agents' test contexts (final_test_seeds)")
    parser.add_argument("--budget", type=int, default=300, help="CMA-ES episodes per context the grid does not solve")
    parser.add_argument("--sigma", type=float, default=0.3, help="CMA-ES initial step (action units)")
    parser.add_argument("--workers", type=int, default=2, help="processes (one context each)")
    parser.add_argument("--seed", type=int, default=0, help="CMA-ES seed")
    add_save_argument(parser)
    return parser.parse_args()


def _episode(env: gym.Env, seed: int, action: np.ndarray) -> dict:
    metrics = run_episode(env, action, seed, None)
    task = metrics["metrics"]
    return {"coverage": task["coverage"], "success": bool(metrics["success"]), "reward": metrics["return"],
            "force_in_band": task["force_in_band_fraction"], "valid": metrics["valid"]}


def _better(a: dict, b: dict | None) -> bool:
    return b is None or (a["success"], a["coverage"]) > (b["success"], b["coverage"])


def search_context(seed: int, budget: int, sigma: float, cma_seed: int) -> dict:
    """Imitation, grid and (if needed) CMA-ES results of one test context (reset seed ``seed``)."""
    env = gym.make(WIPE_ID)
    base = env.unwrapped
    observation, _ = env.reset(seed=seed)
    n = int(env.action_space.shape[0])
    amplitude = base.action_map.slices["amplitude"]
    approach = base.action_map.theta0.size + list(base.action_map.direction_names).index("approach")
    cup = bool(observation[CONTEXT_FIELDS["obstacle"][0]] > 0.5)
    size = observation[slice(CONTEXT_FIELDS["patch_size"][0], sum(CONTEXT_FIELDS["patch_size"]))]
    imitation = _episode(env, seed, np.zeros(n))
    best, best_action, episodes = None, np.zeros(n), 0
    for ax, ay in itertools.product(GRID, GRID):
        action = np.zeros(n)
        action[amplitude.start], action[amplitude.start + 1], action[approach] = ax, ay, 1.0 if cup else 0.0
        result = _episode(env, seed, action)
        episodes += 1
        if _better(result, best):
            best, best_action = result, action
    grid = dict(best)
    searched = None
    if not grid["success"] and budget > 0:
        strategy = cma.CMAEvolutionStrategy(best_action, sigma, {"seed": cma_seed + 1, "bounds": [-1, 1],
                                                                 "verbose": -9, "popsize": 10})
        used = 0
        while used < budget:
            candidates = strategy.ask()
            results = [_episode(env, seed, np.asarray(c)) for c in candidates]
            used += len(candidates)
            for result in results:
                if _better(result, best):
                    best = result
            strategy.tell(candidates, [-(r["coverage"] + r["success"]) for r in results])
            if best["success"]:
                break
        episodes += used
        searched = dict(best)
    env.close()
    return {"seed": seed, "patch_size": size.round(4).tolist(), "cup": cup, "imitation": imitation, "grid": grid,
            "cmaes": searched, "reached": bool(best["success"]), "best_coverage": best["coverage"],
            "episodes": episodes}


def main() -> None:
    args = _parse()
    seeds = [int(s) for s in final_test_seeds(args.test_contexts)]
    with ProcessPoolExecutor(args.workers) as pool:
        rows = list(pool.map(search_context, seeds, [args.budget] * len(seeds), [args.sigma] * len(seeds),
                             [args.seed] * len(seeds)))
    print(f"{'context':>8} {'patch (m)':>13} {'cup':>4} {'imitation':>16} {'grid':>16} {'cmaes':>16}")
    for row in rows:
        cells = [f"{r['coverage']:.3f} {'ok' if r['success'] else '--'}" if r else "-"
                 for r in (row["imitation"], row["grid"], row["cmaes"])]
        size = "x".join(f"{v:.3f}" for v in row["patch_size"])
        print(f"{row['seed'] - seeds[0]:>8} {size:>13} {'yes' if row['cup'] else '':>4} "
              f"{cells[0]:>16} {cells[1]:>16} {cells[2]:>16}")
    reached = np.array([r["reached"] for r in rows], dtype=float)
    grid = np.array([r["grid"]["success"] for r in rows], dtype=float)
    summary = {"imitation": interval(np.array([r["imitation"]["success"] for r in rows], float), "mean").to_dict(),
               "grid": interval(grid, "mean").to_dict(), "reached": interval(reached, "mean").to_dict()}
    print(f"success reachable per context: imitation {summary['imitation']['estimate']:.2f}, amplitude grid + "
          f"approach {summary['grid']['estimate']:.2f}, grid or CMA-ES ({args.budget} episodes) "
          f"{summary['reached']['estimate']:.2f} [{summary['reached']['low']:.2f}, {summary['reached']['high']:.2f}]")
    out = results_dir(args.save) / "feasibility.json"
    out.write_text(json.dumps({"settings": vars(args) | {"env_id": WIPE_ID, "grid": GRID}, "contexts": rows,
                               "summary": summary}, indent=1))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
