"""Figures of the agents layer (matplotlib, Agg backend): learning curves, fits, evaluations."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

__all__ = ["plot_evaluation", "plot_fit", "plot_learning_curve"]


def _column(records: Sequence[dict[str, Any]], key: str) -> np.ndarray:
    return np.array([np.nan if r.get(key) is None else r[key] for r in records], dtype=np.float64)


def plot_learning_curve(records: Sequence[dict[str, Any]], path: str | Path, title: str = "") -> None:
    """Return, coverage and force-in-band of the policy (and of the rollouts) against training episodes."""
    episodes = _column(records, "episodes")
    panels = [("return", "eval_return_mean", "return_mean"), ("coverage", "eval_coverage", "coverage"),
              ("force in band", "eval_force_in_band", "force_in_band")]
    panels = [p for p in panels if np.any(np.isfinite(_column(records, p[1])))]
    figure, axes = plt.subplots(1, len(panels), figsize=(4.2 * len(panels), 3.4), squeeze=False)
    for axis, (label, policy_key, rollout_key) in zip(axes[0], panels, strict=True):
        axis.plot(episodes, _column(records, policy_key), "o-", ms=3, label="policy")
        axis.plot(episodes, _column(records, rollout_key), ".", alpha=0.6, label="rollouts (mean)")
        if label == "return":
            axis.plot(episodes, _column(records, "return_best"), "x", ms=3, alpha=0.5, label="rollouts (best)")
        axis.set_xlabel("training episodes")
        axis.set_ylabel(label)
        axis.grid(alpha=0.3)
    axes[0][0].legend(fontsize=8)
    figure.suptitle(title)
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def plot_fit(t: np.ndarray, demo: np.ndarray, reproduction: np.ndarray, path: str | Path, title: str = "",
             labels: Sequence[str] = ("x", "y", "z")) -> None:
    """Demonstration ``[L, d]`` against the DMP's reproduction ``[L, d]`` over time ``[L]``, plus the x-y path."""
    d = demo.shape[1]
    figure, axes = plt.subplots(1, d + 1, figsize=(3.6 * (d + 1), 3.2))
    for i in range(d):
        axes[i].plot(t, demo[:, i], color="0.6", lw=2.5, label="demonstration")
        axes[i].plot(t, reproduction[:, i], color="C3", lw=1.0, label="DMP")
        axes[i].set_xlabel("t (s)")
        axes[i].set_ylabel(f"{labels[i] if i < len(labels) else i} (m)")
        axes[i].grid(alpha=0.3)
    axes[-1].plot(demo[:, 0], demo[:, 1], color="0.6", lw=2.5)
    axes[-1].plot(reproduction[:, 0], reproduction[:, 1], color="C3", lw=1.0)
    axes[-1].set_aspect("equal", adjustable="datalim")
    axes[-1].set_xlabel("x (m)")
    axes[-1].set_ylabel("y (m)")
    axes[0].legend(fontsize=8)
    rms = float(np.sqrt(np.mean(np.sum((demo - reproduction) ** 2, axis=1))))
    figure.suptitle(f"{title}  (RMS error {1000 * rms:.2f} mm)")
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def plot_evaluation(paths: dict[str, np.ndarray], metrics: dict[str, dict[str, float]], path: str | Path,
                    title: str = "") -> None:
    """Left: x-y paths ``[T, >=2]`` of named policies; right: their mean metrics as grouped bars."""
    figure, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
    for index, (name, points) in enumerate(paths.items()):
        left.plot(points[:, 0], points[:, 1], color=f"C{index}", lw=1.0, label=name)
    left.set_aspect("equal", adjustable="datalim")
    left.set_xlabel("x (m)")
    left.set_ylabel("y (m)")
    left.legend(fontsize=8)
    left.grid(alpha=0.3)
    keys = sorted({key for values in metrics.values() for key in values})
    width = 0.8 / max(len(metrics), 1)
    for index, (name, values) in enumerate(metrics.items()):
        heights = [values.get(key, np.nan) for key in keys]
        right.bar(np.arange(len(keys)) + index * width, heights, width, label=name, color=f"C{index}")
    right.set_xticks(np.arange(len(keys)) + 0.4 - width / 2, keys, fontsize=8)
    right.grid(alpha=0.3, axis="y")
    right.legend(fontsize=8)
    figure.suptitle(title)
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)
