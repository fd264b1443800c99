"""The cost along the ``approach`` dimension where the cup stands on the approach: ``rdmp_gym/ArmarWipe-v2``.

For every test context of the agents' protocol (``--test-contexts``, the benchmark's 50) whose cup stands
between the sponge's start and the patch (its projection on the start-to-patch line before the patch centre),
the imitation's action with only ``approach`` set to each of ``--values``: the return, the control steps the
cup is touched, how far it is pushed (m), coverage and success. Also the share of such contexts among
``--draws`` training contexts. A learner that explores ``approach`` with a standard deviation of 0.3 around its
mean sees the return of neighbouring values: where it barely changes until the approach clears the cup, a small
step gains nothing.

    python benchmarks/bench_cup_plateau.py [--test-contexts 50] [--draws 2000] [--save]
"""

from __future__ import annotations

import argparse
import json
import os

os.environ.setdefault("MUJOCO_GL", "egl")

import gymnasium as gym
import numpy as np
import rdmp_gym.envs  # noqa: F401  (registers the env)
from output import add_save_argument, results_dir
from rdmp_gym.agents.protocol import TRAIN_SEED_LIMIT, context_observations, final_test_seeds

ENV_ID = "rdmp_gym/ArmarWipe-v2"
NAME = "cup_plateau.json"


def on_approach(observations: np.ndarray) -> np.ndarray:
    """``[E]`` whether each context ``[E, 13]`` has a cup before the patch centre on the start-to-patch line."""
    start, patch, cup = observations[:, 7:9], observations[:, 3:5], observations[:, 11:13]
    line = patch - start
    along = np.sum((cup - start) * line, axis=1) / np.sum(line * line, axis=1)
    return (observations[:, 10] > 0.5) & (along < 1.0)


def scan(env: gym.Env, seed: int, values: np.ndarray) -> list[dict]:
    """One episode per ``approach`` value in the context of reset ``seed``, the rest of the action at 0."""
    index = env.unwrapped.action_map.action_slices()["approach"].start
    rows = []
    for value in values:
        action = np.zeros(env.action_space.shape, dtype=np.float32)
        action[index] = value
        env.reset(seed=int(seed))
        _, reward, _, _, info = env.step(action)
        rows.append({"approach": float(value), "return": float(reward),
                     "touch_steps": int(info["obstacle_touch_steps"]), "cup_shift": float(info["obstacle_shift"]),
                     "coverage": float(info["coverage"]), "success": bool(info["is_success"])})
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--test-contexts", type=int, default=50, help="test contexts of the protocol searched")
    parser.add_argument("--draws", type=int, default=2000, help="training contexts drawn for the share")
    parser.add_argument("--values", type=float, nargs="+", default=[-0.2, 0.0, 0.2, 0.4, 0.6, 0.8, 1.0],
                        help="approach values scanned")
    add_save_argument(parser)
    args = parser.parse_args()
    env = gym.make(ENV_ID)
    seeds = final_test_seeds(args.test_contexts)
    chosen = np.flatnonzero(on_approach(context_observations(env, seeds)))
    drawn = np.random.default_rng(0).integers(TRAIN_SEED_LIMIT, size=args.draws)
    share = float(np.mean(on_approach(context_observations(env, drawn))))
    print(f"cup on the approach: {chosen.size} of {seeds.size} test contexts, {share:.3f} of {args.draws} "
          "drawn training contexts")
    contexts = []
    for index in chosen:
        rows = scan(env, int(seeds[index]), np.asarray(args.values))
        contexts.append({"index": int(index), "seed": int(seeds[index]), "scan": rows})
        print(f"test context {index}")
        for row in rows:
            print(f"  approach {row['approach']:+.1f}  return {row['return']:.3f}  touched {row['touch_steps']:3d} "
                  f"steps  cup pushed {row['cup_shift']:.3f} m  coverage {row['coverage']:.3f}  "
                  f"success {row['success']}")
    path = results_dir(args.save) / NAME
    path.write_text(json.dumps({"env_id": ENV_ID, "test_contexts": args.test_contexts, "draws": args.draws,
                                "training_share": share, "contexts": contexts}, indent=1))
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
