"""The figure of both robots drumming (the imitation on one steady-tempo context), with the membrane's force at 500 Hz
and the beats, and optionally a short video of each.

    python benchmarks/drum_figure.py --out docs/assets/drumming.png
    python benchmarks/drum_figure.py --out docs/assets/drumming.png --video runs/drumming   # + one mp4 per robot
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

ROBOTS = {"ARMAR-III (rdmp_gym/ArmarDrum-v1)": "rdmp_gym/ArmarDrum-v1",
          "Franka Panda (rdmp_gym/PandaDrum-v1)": "rdmp_gym/PandaDrum-v1"}
CONTEXT = {"drum_position": [0.05, -0.02], "drum_height": 0.12, "drum_tilt": [0.0, 0.0], "tempo": 90.0,
           "new_tempo": 108.0, "change_time": 4.0}


def episode(env_id: str, video: Path | None) -> tuple[np.ndarray, dict, float]:
    """A frame ``[H, W, 3]`` at the tip's third strike, the episode's info and the control period."""
    env = gym.make(env_id, render_mode="rgb_array", width=560, height=420, frame_stride=4, camera="side")
    face = env.unwrapped
    action = np.zeros(env.action_space.shape, np.float32)
    size = face.action_map.size
    action[size:size + 3] = [0.67, 0.5, -0.5]        # a stronger coupling that follows the tempo change
    env.reset(seed=0, options=CONTEXT)
    if video is not None:
        video.mkdir(parents=True, exist_ok=True)
        _, _, _, _, info = face.record_episode(action, video / f"{env_id.split('/')[1]}.mp4", fps=25)
    else:
        _, _, _, _, info = env.step(action)
    env.reset(seed=0, options=CONTEXT)                # again, keeping the frame of the third strike only
    face.frame_stride = round(float(info["strike_times"][2]) / face.dt)
    face.record_frames = True
    env.step(action)
    face.record_frames = False
    frame = face.frames[1]
    env.close()
    return frame, info, face.dt


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", type=Path, default=Path("runs/drumming.png"))
    parser.add_argument("--video", type=Path, default=None, help="also write one mp4 per robot into this folder")
    args = parser.parse_args()
    figure, axes = plt.subplots(2, 2, figsize=(11, 7.2), gridspec_kw={"height_ratios": [3, 1.3]})
    for column, (title, env_id) in enumerate(ROBOTS.items()):
        frame, info, dt = episode(env_id, args.video)
        axes[0, column].imshow(frame)
        axes[0, column].set_title(title, fontsize=10)
        axes[0, column].axis("off")
        force = info["force_trace"]
        t = (np.arange(len(force)) + 1) * dt / (len(force) / len(info["cost_trace"]))
        ax = axes[1, column]
        ax.plot(t, force, lw=0.8, color="tab:blue", label="membrane force (500 Hz)")
        for beat in info["beat_times"]:
            ax.axvline(beat, color="0.6", lw=0.6, ls=":")
        ax.axvline(info["change_time"], color="tab:red", lw=1.0, label="tempo change")
        ax.set_xlabel("time (s)")
        ax.set_ylabel("force (N)")
        ax.set_title(f"{info['tempo']:.0f} -> {info['new_tempo']:.0f} bpm, struck {info['struck_fraction']:.0%}, "
                     f"success {info['is_success']}", fontsize=9)
        ax.legend(fontsize=7, loc="upper right")
    figure.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
