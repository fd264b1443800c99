"""Probes of the v3 wiping tasks: can cheap or random actions succeed, and what does the task reject?

For each env id: the imitation (action 0) and ``--random`` uniformly random actions on held-out contexts (reset
seeds from 7000), with their success rate, failure causes and jerk ratios; and the settings that make the task
meaningless, each of which must be rejected with an error that names it.

    python benchmarks/bench_v3_probes.py --save            # writes benchmarks/results/v3_probes.json
"""

from __future__ import annotations

import argparse
import json
from collections import Counter

import gymnasium as gym
import numpy as np
import rdmp_gym.envs  # noqa: F401  (registers the ids)
from output import add_save_argument, results_dir

MEANINGLESS = {"target_force": 80.0, "cell_size": 1.0, "cup_clearance": 1.0, "limit_margin": 5.0,
               "control_rate": 2.0, "obstacle": 0.3}


def probe_actions(env_id: str, contexts: int, random: int, seed: int) -> dict:
    """Success and jerk of the imitation and of uniformly random actions on ``contexts`` held-out contexts."""
    env = gym.make(env_id)
    rng = np.random.default_rng(seed)
    rows = {"imitation": [], "random": []}
    for i in range(contexts):
        for kind, count in (("imitation", 1), ("random", random // contexts)):
            for _ in range(count):
                env.reset(seed=7000 + i)
                action = (np.zeros(env.action_space.shape) if kind == "imitation"
                          else rng.uniform(-1.0, 1.0, env.action_space.shape))
                _, reward, _, _, info = env.step(action.astype(np.float32))
                rows[kind].append({"context": 7000 + i, "return": reward, "success": bool(info["is_success"]),
                                   "causes": list(info["failure_causes"]), "jerk_ratio": info["jerk_ratio"]})
    env.close()
    out = {}
    for kind, episodes in rows.items():
        jerk = np.array([r["jerk_ratio"] for r in episodes], dtype=float)
        causes = Counter(c for r in episodes for c in r["causes"])
        out[kind] = {"episodes": len(episodes), "success_rate": float(np.mean([r["success"] for r in episodes])),
                     "mean_return": float(np.mean([r["return"] for r in episodes])),
                     "jerk_ratio_range": [float(np.nanmin(jerk)), float(np.nanmax(jerk))],
                     "failure_causes": dict(causes.most_common())}
    return out


def probe_settings(env_id: str) -> dict:
    """The error each meaningless setting raises (None: accepted)."""
    out = {}
    for key, value in MEANINGLESS.items():
        try:
            gym.make(env_id, **{key: value}).close()
            out[key] = None
        except (TypeError, ValueError) as error:
            out[key] = str(error)
    return out


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--env-id", nargs="+", default=["rdmp_gym/ArmarWipe-v3", "rdmp_gym/PandaWipe-v3"])
    parser.add_argument("--contexts", type=int, default=12)
    parser.add_argument("--random", type=int, default=60)
    parser.add_argument("--seed", type=int, default=0)
    add_save_argument(parser)
    args = parser.parse_args(argv)
    result = {}
    for env_id in args.env_id:
        result[env_id] = {"actions": probe_actions(env_id, args.contexts, args.random, args.seed),
                          "settings": probe_settings(env_id)}
        actions = result[env_id]["actions"]
        print(f"{env_id}: imitation success {actions['imitation']['success_rate']:.2f}, random success "
              f"{actions['random']['success_rate']:.2f} (jerk {actions['random']['jerk_ratio_range'][0]:.1f}-"
              f"{actions['random']['jerk_ratio_range'][1]:.1f}x), causes {actions['random']['failure_causes']}")
        for key, error in result[env_id]["settings"].items():
            print(f"    {key}={MEANINGLESS[key]!r}: {'ACCEPTED' if error is None else error}")
    path = results_dir(args.save) / "v3_probes.json"
    path.write_text(json.dumps({"settings": vars(args), "results": result}, indent=1) + "\n")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
