"""Can every context be wiped, and is the reward's best action a success? A per-context search by the return.

A learned policy maps each context to one action; its success rate on test contexts cannot exceed the share
of contexts where *some* action succeeds. This benchmark estimates that share, the task's ceiling, on the
agents' test contexts (never used for training or selection), and checks that the reward points at success:

- per context, a search maximises the **return** (not a hand-picked score) over the compact action dimensions
  (the amplitudes along the table, the approach's lift, and in ``ArmarWipe-v2`` the sweep's half-extents
  ``sweep_x``, ``sweep_y``), every other dimension at the imitation: a 3 x 3 grid of equal amplitudes x equal
  half-extents (the lift on where a cup stands), then CMA-ES from the grid's best-return action;
- ``solved``: the best-return action found is a success; ``reached``: some evaluated action is a success;
  ``agree``: where an action succeeded, the best-return one did (return and success agree).

A finite search gives a lower bound of the ceiling (a context it does not solve may still be solvable).
Results are cached per context under ``runs/benchmarks/solvable-cache/`` so an interrupted run resumes.

    python benchmarks/bench_solvable.py --save                               # ArmarWipe-v2, 60 contexts
    python benchmarks/bench_solvable.py --env-id rdmp_gym/ArmarWipe-v1 --contexts 20 --save
    python benchmarks/bench_solvable.py --env-id rdmp_gym/PandaWipe-v3 --contexts 50 --budget 32 --save
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
import rdmp_gym.envs  # noqa: F401  (registers the envs)
from output import SCRATCH, add_save_argument, results_dir
from rdmp_gym.agents.protocol import final_test_seeds, interval
from rdmp_gym.agents.tasks import run_episode
from rdmp_gym.envs import ENV_ID_V2
from rdmp_gym.envs.tasks.wiping.context import CONTEXT_FIELDS

COMPACT = ("amplitude_x", "amplitude_y", "approach", "sweep_x", "sweep_y")
#: The first episodes of the search: equal amplitudes along both table axes x equal sweep half-extents.
GRID_AMPLITUDE = (0.0, 0.45, 0.9)
GRID_SWEEP = (0.0, 0.33, 0.67)


def _parse() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--env-id", default=ENV_ID_V2, help="a wiping env id (ArmarWipe-v2, PandaWipe-v3, ...)")
    parser.add_argument("--contexts", type=int, default=60, help="test contexts (the agents' final_test_seeds)")
    parser.add_argument("--budget", type=int, default=64, help="CMA-ES episodes per context")
    parser.add_argument("--sigma", type=float, default=0.3, help="CMA-ES initial step (action units)")
    parser.add_argument("--workers", type=int, default=2, help="processes (one context each)")
    parser.add_argument("--seed", type=int, default=0, help="CMA-ES seed")
    parser.add_argument("--figure", action="store_true", help="also draw the sponge's path on the largest patch")
    add_save_argument(parser)
    return parser.parse_args()


def compact_indices(env: gym.Env) -> dict[str, int]:
    """``{name: action index}`` of the compact dimensions the env has (see :data:`COMPACT`)."""
    slices = env.unwrapped.action_map.action_slices()
    found = {"amplitude_x": slices["amplitude"].start, "amplitude_y": slices["amplitude"].start + 1}
    found.update({name: slices[name].start for name in COMPACT[2:] if name in slices})
    return found


def best_action(env: gym.Env, row: dict) -> np.ndarray:
    """The full action ``[n]`` of a row's best compact action (every other dimension 0)."""
    action = np.zeros(env.action_space.shape[0])
    for name, index in compact_indices(env).items():
        action[index] = row["best_action"][name]
    return action


def _metrics(env: gym.Env, seed: int, action: np.ndarray) -> dict:
    metrics = run_episode(env, action, seed, None)
    task = metrics["metrics"]
    return {"return": metrics["return"], "coverage": task["coverage"], "success": bool(metrics["success"]),
            "force_in_band": task["force_in_band_fraction"], "valid": metrics["valid"]}


def search_context(env_id: str, seed: int, budget: int, sigma: float, cma_seed: int) -> dict:
    """The imitation's and the best-return action's results in the test context of reset seed ``seed``."""
    env = gym.make(env_id)
    observation, _ = env.reset(seed=seed)
    index = compact_indices(env)
    n = int(env.action_space.shape[0])
    cup = bool(observation[CONTEXT_FIELDS["obstacle"][0]] > 0.5)
    start = np.array([1.0 if (name == "approach" and cup) else 0.0 for name in index])

    def full(x: np.ndarray) -> np.ndarray:
        action = np.zeros(n)
        action[list(index.values())] = np.clip(x, -1.0, 1.0)
        return action

    imitation = _metrics(env, seed, np.zeros(n))
    evaluated = []
    for amplitude, extent in itertools.product(GRID_AMPLITUDE, GRID_SWEEP if "sweep_x" in index else (0.0,)):
        x = start.copy()
        x[:2] = amplitude
        x[3:] = extent
        evaluated.append((x, _metrics(env, seed, full(x))))
    start = max(evaluated, key=lambda item: item[1]["return"])[0]
    strategy = cma.CMAEvolutionStrategy(start, sigma, {"seed": cma_seed + 1, "bounds": [-1, 1], "verbose": -9,
                                                      "popsize": 8})
    while len(evaluated) < budget:
        candidates = strategy.ask()
        results = [_metrics(env, seed, full(np.asarray(c))) for c in candidates]
        evaluated += list(zip(candidates, results, strict=True))
        strategy.tell(candidates, [-r["return"] for r in results])
    env.close()
    best_x, best = max(evaluated, key=lambda item: item[1]["return"])
    reached = any(r["success"] for _, r in evaluated)
    size = observation[slice(CONTEXT_FIELDS["patch_size"][0], sum(CONTEXT_FIELDS["patch_size"]))]
    return {"seed": seed, "patch_size": size.round(4).tolist(), "cup": cup, "imitation": imitation, "best": best,
            "best_action": {name: float(v) for name, v in zip(index, np.clip(best_x, -1, 1), strict=True)},
            "solved": best["success"], "reached": reached, "agree": best["success"] or not reached,
            "episodes": len(evaluated)}


def _cached(args: argparse.Namespace, seed: int) -> dict:
    """:func:`search_context`, read from / written to the per-context cache (resumable runs)."""
    tag = f"{args.env_id.replace('/', '_')}-b{args.budget}-s{args.sigma:g}-c{args.seed}"
    path = SCRATCH / "solvable-cache" / tag / f"{seed}.json"
    if path.is_file():
        return json.loads(path.read_text())
    row = search_context(args.env_id, seed, args.budget, args.sigma, args.seed)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(row))
    return row


def _table(rows: list[dict], first: int) -> None:
    print(f"{'context':>7} {'patch (m)':>11} {'cup':>4} {'imitation':>20} {'best return':>20}  best action")
    for row in rows:
        cells = [f"{r['return']:6.3f} {r['coverage']:.3f} {'ok' if r['success'] else '--'}"
                 for r in (row["imitation"], row["best"])]
        size = "x".join(f"{v:.2f}" for v in row["patch_size"])
        action = " ".join(f"{k}={v:+.2f}" for k, v in row["best_action"].items())
        print(f"{row['seed'] - first:>7} {size:>11} {'yes' if row['cup'] else '':>4} {cells[0]:>20} {cells[1]:>20}  "
              f"{action}")


def main() -> None:
    args = _parse()
    seeds = [int(s) for s in final_test_seeds(args.contexts)]
    with ProcessPoolExecutor(args.workers) as pool:
        rows = list(pool.map(_cached, [args] * len(seeds), seeds))
    _table(rows, seeds[0])
    summary = {key: interval(np.array([r[key] for r in rows], dtype=float), "mean").to_dict()
               for key in ("solved", "reached", "agree")}
    summary["imitation"] = interval(np.array([r["imitation"]["success"] for r in rows], float), "mean").to_dict()
    for key, text in (("imitation", "imitation succeeds"), ("solved", "best-return action succeeds"),
                      ("reached", "some action succeeds"), ("agree", "return and success agree")):
        part = summary[key]
        print(f"{text:>28}: {part['estimate']:.3f} [{part['low']:.3f}, {part['high']:.3f}] of {part['n']} contexts")
    task, version = args.env_id.split("/")[-1].rsplit("-", 1)
    robot = task.removesuffix("Wipe").lower()                      # ArmarWipe-v2 -> solvable_v2 (as published)
    name = f"solvable_{version}" if robot == "armar" else f"solvable_{robot}_{version}"
    out = results_dir(args.save) / f"{name}.json"
    out.write_text(json.dumps({"settings": vars(args), "contexts": rows, "summary": summary}, indent=1))
    print(f"wrote {out}")
    if args.figure:
        from solvable_figure import draw_paths

        row = max(rows, key=lambda r: float(np.prod(r["patch_size"])))
        env = gym.make(args.env_id)
        figure = draw_paths(env, row, best_action(env, row), results_dir(args.save) / f"{name}_path.png")
        print(f"wrote {figure}")


if __name__ == "__main__":
    main()
