"""The drumming task attacked and searched: can cheap strategies succeed, and can every test context be drummed?

Probes (per robot, contexts drawn with reset seeds 9000...; none may succeed):

- ``standing still``: the stick held at its start for the whole episode;
- ``pressing on the membrane``: the imitation's approach, then the tip held 5 mm into the membrane's centre;
- ``hammering at the fastest tempo``: the DMP drumming at 150 bpm, deaf to the metronome;
- ``striking at random``: the DMP following a metronome of a random tempo and a random change (not the real one);
- ``jagged actions``: every action dimension at -1 or +1, signs drawn at random;
- ``uniformly random actions``: actions drawn uniformly from the action box (24 contexts).

Solvability (the agents' 50 test contexts, ``final_test_seeds``): the imitation (action 0), then a search by the
**return** over the compact dimensions (the coupling gain, the phase gain, the beat's phase shift and the three
amplitudes; every other dimension at the imitation): a grid over the three rhythm dimensions, then CMA-ES from the
grid's best. ``solved``: the best-return action found is a success; ``reached``: some evaluated action is;
``agree``: where one succeeded, the best-return one did. Results are cached per context under
``runs/benchmarks/drum-cache/`` so an interrupted run resumes.

    python benchmarks/bench_drum.py --save                        # both robots, about 25 min on 2 cores
    python benchmarks/bench_drum.py --robots armar3 --contexts 10 # a quick look
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import cma
import gymnasium as gym
import numpy as np
import rdmp_gym.envs  # noqa: F401  (registers the envs)
from output import SCRATCH, add_save_argument, results_dir
from rdmp_gym.agents.protocol import final_test_seeds, interval
from rdmp_gym.envs.registration import task_ids

PROBE_SEED = 9000
GRID = {"coupling": (0.0, 0.5, 0.8), "phase_gain": (0.0, 0.5, 0.8), "phase": (0.0, -0.5)}


def _parse() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--robots", nargs="+", default=["armar3", "panda"])
    parser.add_argument("--contexts", type=int, default=50, help="test contexts (the agents' final_test_seeds)")
    parser.add_argument("--probe-contexts", type=int, default=12)
    parser.add_argument("--budget", type=int, default=64, help="CMA-ES episodes per context after the grid")
    parser.add_argument("--workers", type=int, default=2)
    add_save_argument(parser)
    return parser.parse_args()


def _outcome(reward: float, info: dict) -> dict:
    return {"return": float(reward), "success": bool(info["is_success"]), "causes": list(info["failure_causes"]),
            "struck": float(info.get("struck_fraction", 0.0))}


def _episode(env: gym.Env, seed: int, action: np.ndarray) -> dict:
    env.reset(seed=int(seed))
    _, reward, _, _, info = env.step(np.asarray(action, dtype=np.float32))
    return _outcome(reward, info)


def _probe(robot: str, name: str, seed: int) -> dict:
    """One probe episode in the context of reset seed ``seed``."""
    env = gym.make(task_ids("drum", robot, 1)[0])
    face = env.unwrapped
    rng = np.random.default_rng(seed)
    n = env.action_space.shape[0]
    if name == "uniformly random actions":
        return _episode(env, seed, rng.uniform(-1, 1, n))
    if name == "jagged actions":
        return _episode(env, seed, rng.choice([-1.0, 1.0], n))
    face.reset(seed=int(seed))
    imitation = face.imitation_plan.path
    if name == "standing still":
        path = np.repeat(imitation[:1], len(imitation), axis=0)
    elif name == "pressing on the membrane":
        blend = np.clip((face.times - 1.0) / 0.8, 0.0, 1.0)[:, None]
        smooth = blend**3 * (10 - 15 * blend + 6 * blend**2)
        path = imitation + smooth * (np.array([0.0, 0.0, -0.005]) - imitation)
    else:
        context = face.context
        if name == "hammering at the fastest tempo":
            heard = replace(context, tempo=150.0, new_tempo=150.0, change_time=np.inf)
        else:
            tempo = rng.uniform(60.0, 120.0)
            heard = replace(context, tempo=tempo, new_tempo=tempo * rng.uniform(0.8, 1.25),
                            change_time=rng.uniform(3.5, 5.5))
        theta0 = face.action_map.theta0
        path = face.task.plan(face.dmp, theta0, np.zeros(len(face.extra_scales)), heard, face.times,
                              face.scene.table_origin).path
    return _outcome(*face.run_path(path))


def _compact(env: gym.Env) -> list[int]:
    """Action indices of the coupling gain, the phase gain, the phase shift and the three amplitudes."""
    face = env.unwrapped
    n = face.action_map.size
    amplitude = face.action_map.action_slices()["amplitude"]
    return [n, n + 1, n + 2, *range(amplitude.start, amplitude.stop)]


def search_context(robot: str, seed: int, budget: int) -> dict:
    """The imitation's and the best-return action's results in the test context of reset seed ``seed``."""
    env = gym.make(task_ids("drum", robot, 1)[0])
    n = env.action_space.shape[0]
    index = _compact(env)

    def full(x: np.ndarray) -> np.ndarray:
        action = np.zeros(n)
        action[index] = np.clip(x, -1.0, 1.0)
        return action

    imitation = _episode(env, seed, np.zeros(n))
    evaluated = [(np.zeros(len(index)), imitation)]
    for values in itertools.product(*GRID.values()):
        x = np.r_[values, np.zeros(3)]
        evaluated.append((x, _episode(env, seed, full(x))))
    start = max(evaluated, key=lambda item: item[1]["return"])[0]
    strategy = cma.CMAEvolutionStrategy(start, 0.25, {"seed": seed % 10_000 + 1, "bounds": [-1, 1], "verbose": -9,
                                                      "popsize": 8})
    while len(evaluated) < 1 + len(list(itertools.product(*GRID.values()))) + budget:
        candidates = strategy.ask()
        results = [_episode(env, seed, full(np.asarray(c))) for c in candidates]
        evaluated += list(zip(candidates, results, strict=True))
        strategy.tell(candidates, [-r["return"] for r in results])
    env.close()
    best_x, best = max(evaluated, key=lambda item: item[1]["return"])
    reached = any(r["success"] for _, r in evaluated)
    first = next((i for i, (_, r) in enumerate(evaluated) if r["success"]), None)
    return {"seed": int(seed), "imitation": imitation, "best": best, "best_compact": np.clip(best_x, -1, 1).tolist(),
            "solved": best["success"], "reached": reached, "agree": best["success"] or not reached,
            "episodes_to_success": first, "episodes": len(evaluated)}


def _probe_row(rows: list[dict]) -> dict:
    return {"successes": int(sum(r["success"] for r in rows)), "episodes": len(rows),
            "mean_return": float(np.mean([r["return"] for r in rows]))}


def _cached(function, path, *args) -> dict:
    if path.is_file():
        return json.loads(path.read_text())
    row = function(*args)
    path.write_text(json.dumps(row))
    return row


def main() -> None:
    args = _parse()
    cache = SCRATCH / "drum-cache"
    cache.mkdir(parents=True, exist_ok=True)
    probes = ("standing still", "pressing on the membrane", "hammering at the fastest tempo", "striking at random",
              "jagged actions", "uniformly random actions")
    results: dict = {"probes": {}, "solvable": {}}
    with ProcessPoolExecutor(args.workers) as pool:
        for robot in args.robots:
            jobs = {}
            for name in probes:
                count = 24 if name == "uniformly random actions" else args.probe_contexts
                for seed in range(PROBE_SEED, PROBE_SEED + count):
                    path = cache / f"probe-{robot}-{name.replace(' ', '_')}-{seed}.json"
                    jobs[(name, seed)] = pool.submit(_cached, _probe, path, robot, name, seed)
            rows = {key: job.result() for key, job in jobs.items()}
            results["probes"][robot] = {name: _probe_row([r for (p, _), r in rows.items() if p == name])
                                        for name in probes}
            seeds = final_test_seeds(args.contexts)
            jobs = {seed: pool.submit(_cached, search_context, cache / f"search-{robot}-{seed}-{args.budget}.json",
                                      robot, int(seed), args.budget) for seed in seeds}
            rows = [jobs[seed].result() for seed in seeds]
            imitation = np.array([r["imitation"]["success"] for r in rows], dtype=float)
            results["solvable"][robot] = {
                "contexts": len(rows), "solved": int(sum(r["solved"] for r in rows)),
                "reached": int(sum(r["reached"] for r in rows)), "agree": int(sum(r["agree"] for r in rows)),
                "imitation_success": float(imitation.mean()),
                "imitation_interval": interval(imitation, statistic="mean").to_dict(),
                "median_episodes_to_success": float(np.median([r["episodes_to_success"] for r in rows
                                                               if r["episodes_to_success"] is not None] or [np.nan])),
                "rows": rows}
    _report(results)
    out = results_dir(args.save) / "drum.json"
    out.write_text(json.dumps(results, indent=1) + "\n")
    print(f"wrote {out}")


def _report(results: dict) -> None:
    for robot, table in results["probes"].items():
        print(f"\nprobes on {robot}: successes / episodes (mean return)")
        for name, row in table.items():
            print(f"  {name:32s} {row['successes']:2d} / {row['episodes']:2d}   ({row['mean_return']:.2f})")
    for robot, row in results["solvable"].items():
        low, high = row["imitation_interval"]["low"], row["imitation_interval"]["high"]
        print(f"\n{robot}: imitation {row['imitation_success']:.2f} [{low:.2f}, {high:.2f}] on {row['contexts']} test "
              f"contexts; the search solves {row['solved']}, reaches {row['reached']}, best-return agrees on "
              f"{row['agree']}; median episodes to a success {row['median_episodes_to_success']}")


if __name__ == "__main__":
    main()
