"""Demo of rdmp_gym/ArmarWipe-v1: the imitation wipes, force adaptation copes with a lower table,
a random action perturbs the DMP, and (optionally) an episode is written to a video.

Run headless with ``MUJOCO_GL=egl python examples/wipe_env_demo.py [--video runs/wipe.mp4]``.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import gymnasium as gym
import numpy as np
import rdmp_gym.envs  # noqa: F401  (registers rdmp_gym/ArmarWipe-v1)


def summary(name: str, reward: float, info: dict) -> str:
    return (f"{name:34s} reward {reward:6.3f}  coverage {info['coverage']:5.3f}  force {info['force_mean']:5.1f} N  "
            f"in band {info['force_in_band_fraction']:4.2f}  valid {info['valid']}  success {info['is_success']}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--style", type=int, default=1, help="demonstration style 1..4")
    parser.add_argument("--video", type=Path, default=None, help="write one episode to this .mp4/.gif")
    args = parser.parse_args()

    env = gym.make("rdmp_gym/ArmarWipe-v1", style=args.style, n_periods=4, render_mode="rgb_array")
    rigid = gym.make("rdmp_gym/ArmarWipe-v1", style=args.style, n_periods=4, adaptation=False)
    zero = np.zeros(env.action_space.shape, dtype=np.float32)
    print(f"action dim {env.action_space.shape[0]}, context {env.observation_space.shape[0]}, "
          f"{env.unwrapped.n_steps} control steps at {env.unwrapped.control_rate:.0f} Hz")

    obs, _ = env.reset(seed=0)
    print("context:", np.round(obs, 3))
    _, reward, _, _, info = env.step(zero)
    print(summary("imitation (action 0)", reward, info))
    print("   reward terms:", {k: round(v, 4) for k, v in info["reward_terms"].items() if v})

    lower = {"table_height": -0.03, "patch_size": [0.12, 0.12]}
    for name, environment in (("table 3 cm lower, adaptation", env), ("table 3 cm lower, no adaptation", rigid)):
        environment.reset(seed=1, options=lower)
        _, reward, _, _, info = environment.step(zero)
        print(summary(name, reward, info))

    env.reset(seed=2)
    action = env.action_space.sample()
    _, reward, _, _, info = env.step(action)
    print(summary("random action", reward, info))

    if args.video is not None:
        env.reset(seed=0)
        env.unwrapped.record_episode(zero, args.video)
        print(f"video: {args.video} ({len(env.unwrapped.frames)} frames)")
    env.close()
    rigid.close()


if __name__ == "__main__":
    main()
