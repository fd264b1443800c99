"""The figure of both robots wiping the same table (the imitation, mid-wipe, on the same context).

    python benchmarks/robots_figure.py --out docs/assets/robots.png
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import gymnasium as gym
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import rdmp_gym.envs  # noqa: F401  (registers the ids)

ROBOTS = {"ARMAR-III (rdmp_gym/ArmarWipe-v3)": "rdmp_gym/ArmarWipe-v3",
          "Franka Panda (rdmp_gym/PandaWipe-v3)": "rdmp_gym/PandaWipe-v3"}


def frame(env_id: str, seed: int, at: float, camera: str) -> np.ndarray:
    """An RGB frame ``[H, W, 3]`` of the imitation's episode at the fraction ``at`` of its length."""
    env = gym.make(env_id, render_mode="rgb_array", camera=camera, width=640, height=480, frame_stride=10)
    env.reset(seed=seed)
    env.unwrapped.record_frames = True
    env.step(np.zeros(env.action_space.shape, np.float32))
    frames = env.unwrapped.frames
    env.close()
    return frames[min(len(frames) - 1, int(at * len(frames)))]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", type=Path, default=Path("docs/assets/robots.png"))
    parser.add_argument("--seed", type=int, default=7006, help="reset seed of the context")
    parser.add_argument("--at", type=float, default=0.55, help="moment of the episode (fraction of its length)")
    parser.add_argument("--camera", default="front")
    args = parser.parse_args()
    fig, axes = plt.subplots(1, len(ROBOTS), figsize=(6.4 * len(ROBOTS), 4.8))
    for ax, (title, env_id) in zip(axes, ROBOTS.items(), strict=True):
        ax.imshow(frame(env_id, args.seed, args.at, args.camera))
        ax.set_title(title)
        ax.axis("off")
    fig.tight_layout(rect=(0, 0, 1, 0.95))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=80)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
