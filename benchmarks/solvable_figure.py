"""The sponge's path in one context of a ``bench_solvable`` run: the imitation's loop in place against the
best-return action's travelling pattern (drawn by ``bench_solvable.py --figure`` on the largest patch)."""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt
from matplotlib.patches import Circle, Rectangle

__all__ = ["draw_paths"]


def draw_paths(env: gym.Env, row: dict, action: np.ndarray, path: Path) -> Path:
    """Draw the patch, the cup, the imitation's and ``action``'s sponge paths (table plane, only where the sponge
    is within 1 cm of the table) in ``row``'s context (``env`` is reset to it); returns ``path`` (PNG)."""
    env.reset(seed=row["seed"])
    base = env.unwrapped
    imitation, best = base.task.imitation_path(base.context), base.rollout_path(base.action_to_params(action))
    context = env.unwrapped.context
    figure, axis = plt.subplots(figsize=(6, 6))
    low = context.patch_centre - context.patch_size / 2
    axis.add_patch(Rectangle(low, *context.patch_size, color="saddlebrown", alpha=0.25, label="dirt patch"))
    if context.obstacle:
        radius = env.unwrapped.task.parts.obstacle_radius
        axis.add_patch(Circle(context.obstacle_position, radius, color="tab:red", alpha=0.4, label="cup"))
    for trace, colour, label in ((imitation, "tab:gray", "imitation (action 0)"),
                                 (best, "tab:blue", "best return")):
        on = trace[:, 2] < 0.01
        xy = np.where(on[:, None], trace[:, :2], np.nan)
        axis.plot(xy[:, 0], xy[:, 1], color=colour, lw=1.0, label=f"{label}: sponge centre on the table")
    result, name = row["best"], env.spec.id if env.spec else "ArmarWipe"
    axis.set_title(f"{name}, patch {row['patch_size'][0]:.2f} x {row['patch_size'][1]:.2f} m\n"
                   f"imitation coverage {row['imitation']['coverage']:.2f}, best return {result['return']:.2f} "
                   f"coverage {result['coverage']:.2f} ({'success' if result['success'] else 'no success'})",
                   fontsize=9)
    axis.set_xlabel("table x (m)")
    axis.set_ylabel("table y (m)")
    axis.set_aspect("equal")
    axis.legend(fontsize=7, loc="upper right")
    figure.tight_layout()
    figure.savefig(path, dpi=120)
    plt.close(figure)
    return path
