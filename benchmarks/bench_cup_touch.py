"""Which part of the hand knocks the cup, and what the clearance term changes: ``rdmp_gym/ArmarWipe-v2``.

For every test context of the agents' protocol (``--test-contexts``, the benchmark's 50) that has a cup, two
actions (the imitation, and a wider travelling pattern as the learners make it) are run twice: as commanded,
and with the env's clearance term (``cup_clearance=--margin``). Per context: the control steps the cup is
touched, which part of the hand (fingers, thumb, palm, sponge) comes nearest to the cup's side in the planned
posture (``hand_cup_gaps``) and how near, and with the clearance term the touches, the largest push of the
path, coverage, success and the jerk ratio.

    python benchmarks/bench_cup_touch.py [--test-contexts 50] [--margin 0.01] [--save]
"""

from __future__ import annotations

import argparse
import json
import os
from collections import Counter

os.environ.setdefault("MUJOCO_GL", "egl")

import gymnasium as gym
import numpy as np
import rdmp_gym.envs  # noqa: F401  (registers the env)
from output import add_save_argument, results_dir
from rdmp_gym.agents.protocol import final_test_seeds

ENV_ID = "rdmp_gym/ArmarWipe-v2"
NAME = "cup_touch.json"
#: the actions compared: the imitation, and a wider, travelling pattern as the learners make it (the amplitude
#: in x and y and both sweep half-axes at +0.5)
ACTIONS = {"imitation": {}, "wider": {"amplitude": (0.5, 0.5), "sweep_x": (0.5,), "sweep_y": (0.5,)}}


def action(env: gym.Env, setting: dict) -> np.ndarray:
    """``[A]`` the action with the leading dimensions of each named group set, 0 elsewhere."""
    out = np.zeros(env.action_space.shape, dtype=np.float32)
    slices = env.unwrapped.action_map.action_slices()
    for group, values in setting.items():
        out[slices[group].start:slices[group].start + len(values)] = values
    return out


def nearest_part(env: gym.Env, act: np.ndarray) -> tuple[str, float]:
    """(part, gap in m) of the hand part that comes nearest to the cup's side along the path of ``act``."""
    base = env.unwrapped
    gaps = base.task.hand_cup_gaps(base.rollout_path(base.action_to_params(act)), base.context)
    closest = {part: float(np.min(gap)) for part, gap in gaps.items()}
    part = min(closest, key=closest.get)
    return part, closest[part]


def episode(env: gym.Env, seed: int, act: np.ndarray) -> dict:
    """The figures of ``act``'s episode in the context of ``seed``."""
    env.reset(seed=seed)
    _, reward, _, _, info = env.step(act)
    return {"touch_steps": int(info["obstacle_touch_steps"]), "coverage": float(info["coverage"]),
            "success": bool(info["is_success"]), "jerk_ratio": float(info["jerk_ratio"]), "return": float(reward),
            "push": float(info.get("clearance_push", 0.0))}


def compare(plain: gym.Env, guarded: gym.Env, seeds: np.ndarray, act: np.ndarray) -> dict:
    """Per cup context of ``seeds``: ``act`` as commanded and with the clearance term, and a summary."""
    rows = []
    for index, seed in enumerate(seeds):
        plain.reset(seed=int(seed))
        if not plain.unwrapped.context.obstacle:
            continue
        part, gap = nearest_part(plain, act)
        rows.append({"context": index, "seed": int(seed), "nearest_part": part, "nearest_gap": gap,
                     "plain": episode(plain, int(seed), act), "clearance": episode(guarded, int(seed), act)})
    touched = [row for row in rows if row["plain"]["touch_steps"] > 0]
    summary = {
        "cup_contexts": len(rows), "touched": len(touched),
        "nearest_part_when_touched": dict(Counter(row["nearest_part"] for row in touched)),
        "touched_with_clearance": sum(row["clearance"]["touch_steps"] > 0 for row in rows),
        "success": {kind: int(sum(row[kind]["success"] for row in rows)) for kind in ("plain", "clearance")},
        "coverage_change_mean": float(np.mean([row["clearance"]["coverage"] - row["plain"]["coverage"]
                                               for row in rows])),
        "jerk_ratio_median": {kind: float(np.median([row[kind]["jerk_ratio"] for row in rows]))
                              for kind in ("plain", "clearance")},
        "push_max": float(max(row["clearance"]["push"] for row in rows)),
    }
    return {"summary": summary, "contexts": rows}


def measure(n_contexts: int, margin: float) -> dict:
    plain, guarded = gym.make(ENV_ID), gym.make(ENV_ID, cup_clearance=margin)
    seeds = final_test_seeds(n_contexts)
    return {"env": ENV_ID, "margin": margin, "test_contexts": n_contexts, "actions": ACTIONS,
            "results": {name: compare(plain, guarded, seeds, action(plain, setting))
                        for name, setting in ACTIONS.items()}}


def print_table(result: dict) -> None:
    for name, res in result["results"].items():
        s = res["summary"]
        print(f"{name}: {s['cup_contexts']} cup contexts, the cup touched in {s['touched']} "
              f"(nearest part there: {s['nearest_part_when_touched']}); with the clearance term touched in "
              f"{s['touched_with_clearance']}, success {s['success']['plain']} -> {s['success']['clearance']}, "
              f"coverage {s['coverage_change_mean']:+.4f} on average, median jerk ratio "
              f"{s['jerk_ratio_median']['plain']:.3f} -> {s['jerk_ratio_median']['clearance']:.3f}, "
              f"largest push {100 * s['push_max']:.1f} cm")
        for row in res["contexts"]:
            p, c = row["plain"], row["clearance"]
            if p["touch_steps"] or c["touch_steps"]:
                print(f"  context {row['context']:>2}: {row['nearest_part']:>7} {100 * row['nearest_gap']:+5.1f} cm, "
                      f"touched {p['touch_steps']:>3} -> {c['touch_steps']:>3} steps, coverage {p['coverage']:.3f} -> "
                      f"{c['coverage']:.3f}, push {100 * c['push']:.1f} cm")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--test-contexts", type=int, default=50)
    parser.add_argument("--margin", type=float, default=0.01, help="the clearance term's margin (m)")
    add_save_argument(parser)
    args = parser.parse_args()
    result = measure(args.test_contexts, args.margin)
    print_table(result)
    (results_dir(args.save) / NAME).write_text(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
