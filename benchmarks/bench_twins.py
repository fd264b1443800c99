"""The step twins against their episodic envs: the twin's zero action is the episodic action 0, on held-out contexts.

For every task and robot (the wiping v3 tasks and the drumming tasks by default) and every context (reset seeds
7000...), one episode of the episodic env with action 0 and one of its step twin with the zero action throughout;
the twin's return (the sum of its step rewards), ``is_success`` and failure causes must equal the episodic env's.

    python benchmarks/bench_twins.py --save          # 12 contexts x 4 envs, a few minutes on 2 cores
"""

from __future__ import annotations

import argparse
import json
import os

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import gymnasium as gym
import numpy as np
import rdmp_gym.envs  # noqa: F401  (registers the ids)
from output import add_save_argument, results_dir

PAIRS = {"rdmp_gym/ArmarWipe-v3": "rdmp_gym/ArmarWipeStep-v3", "rdmp_gym/PandaWipe-v3": "rdmp_gym/PandaWipeStep-v3",
         "rdmp_gym/ArmarDrum-v1": "rdmp_gym/ArmarDrumStep-v1", "rdmp_gym/PandaDrum-v1": "rdmp_gym/PandaDrumStep-v1"}


def compare(episodic_id: str, step_id: str, seeds: list[int]) -> list[dict]:
    """Per context: the episodic action 0's and the twin's zero action's return, success and failure causes."""
    episodic, twin = gym.make(episodic_id), gym.make(step_id)
    rows = []
    for seed in seeds:
        episodic.reset(seed=seed)
        _, reward, _, _, info = episodic.step(np.zeros(episodic.action_space.shape, np.float32))
        twin.reset(seed=seed)
        total, done = 0.0, False
        while not done:
            _, step_reward, terminated, truncated, step_info = twin.step(np.zeros(twin.action_space.shape))
            total, done = total + step_reward, terminated or truncated
        rows.append({"seed": seed, "episodic_return": float(reward), "twin_return": float(total),
                     "episodic_success": bool(info["is_success"]), "twin_success": bool(step_info["is_success"]),
                     "episodic_causes": list(info["failure_causes"]), "twin_causes": list(step_info["failure_causes"]),
                     "agree": bool(np.isclose(reward, total, rtol=1e-9, atol=1e-9)
                                   and info["is_success"] == step_info["is_success"]
                                   and tuple(info["failure_causes"]) == tuple(step_info["failure_causes"]))})
    episodic.close()
    twin.close()
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--env-id", nargs="+", default=list(PAIRS), help="episodic ids (their twins are known)")
    parser.add_argument("--contexts", type=int, default=12)
    add_save_argument(parser)
    args = parser.parse_args()
    seeds = list(range(7000, 7000 + args.contexts))
    results = {env_id: compare(env_id, PAIRS[env_id], seeds) for env_id in args.env_id}
    print(f"{'episodic env':>24} {'agree':>7} {'episodic successes':>19} {'twin successes':>15}")
    for env_id, rows in results.items():
        print(f"{env_id:>24} {sum(r['agree'] for r in rows):>3}/{len(rows):<3} "
              f"{sum(r['episodic_success'] for r in rows):>19} {sum(r['twin_success'] for r in rows):>15}")
    path = results_dir(args.save) / "twins.json"
    path.write_text(json.dumps({"settings": vars(args), "results": results}, indent=1) + "\n")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
