"""Figures of the agents layer (matplotlib, Agg backend): learning curves, fits, evaluations."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from rdmp_gym.signals.filters import smooth_derivatives

__all__ = ["plot_fit", "plot_learning_curve", "plot_policy_comparison", "plot_recording_fit"]


def _column(records: Sequence[dict[str, Any]], key: str) -> np.ndarray:
    return np.array([np.nan if r.get(key) is None else r[key] for r in records], dtype=np.float64)


def plot_learning_curve(records: Sequence[dict[str, Any]], path: str | Path, title: str = "") -> None:
    """Return, coverage and force-in-band of the policy (and of the rollouts) against training episodes."""
    episodes = _column(records, "episodes")
    panels = [("return", "eval_return_mean", "return_mean"), ("success rate", "eval_success", "success"),
              ("coverage", "eval_coverage", "coverage"), ("force in band", "eval_force_in_band", "force_in_band")]
    panels = [p for p in panels if np.any(np.isfinite(_column(records, p[1])))]
    figure, axes = plt.subplots(1, len(panels), figsize=(4.2 * len(panels), 3.4), squeeze=False)
    for axis, (label, policy_key, rollout_key) in zip(axes[0], panels, strict=True):
        values = _column(records, policy_key)
        shown = np.isfinite(values)      # the policy is evaluated every eval_every updates
        axis.plot(episodes[shown], values[shown], "o-", ms=3, label="policy (validation contexts)")
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


def plot_recording_fit(t: np.ndarray, recording: np.ndarray, reproduce, path: str | Path, title: str = "",
                       labels: Sequence[str] = ("x", "y", "z")) -> None:
    """A recording ``[L, d]`` at even times ``t [L]`` (from 0) against a reproduction (``reproduce(times) -> [T, d]``):
    positions per dimension, and the acceleration's norm (the recording's Savitzky-Golay-smoothed over 0.15 s,
    the reproduction's from a 1 kHz rollout)."""
    dt = float(t[1] - t[0])
    reproduction = reproduce(t)
    fine = np.arange(0.0, t[-1], 1e-3)
    acceleration = np.linalg.norm(np.diff(reproduce(fine), 2, axis=0), axis=1) / 1e-6
    recorded = np.linalg.norm(smooth_derivatives(recording, dt, 0.15)[2], axis=1)
    d = recording.shape[1]
    figure, axes = plt.subplots(d + 1, 1, figsize=(11, 2.0 * (d + 1)), sharex=True)
    for i in range(d):
        axes[i].plot(t, recording[:, i], color="0.6", lw=2.5, label="recording")
        axes[i].plot(t, reproduction[:, i], color="C3", lw=1.0, label="DMP")
        axes[i].set_ylabel(f"{labels[i] if i < len(labels) else i} (m)")
        axes[i].grid(alpha=0.3)
    axes[-1].plot(t, recorded, color="0.6", lw=1.5, label="recording (smoothed)")
    axes[-1].plot(fine[1:-1], acceleration, color="C3", lw=1.0, label="DMP")
    axes[-1].set_ylabel("|acceleration| (m/s²)")
    axes[-1].set_xlabel("t (s)")
    axes[-1].grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    axes[-1].legend(fontsize=8)
    figure.suptitle(title)
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def plot_policy_comparison(paths: dict[str, np.ndarray], summaries: dict[str, dict[str, Any]], path: str | Path,
                           title: str = "") -> None:
    """Sponge paths ``[T, >=2]`` of named policies side by side (same axes), then their success rate,
    coverage and jerk ratio with 95 % intervals (``summaries[name]["intervals"][metric]``)."""
    figure, axes = plt.subplots(1, len(paths) + 1, figsize=(4.2 * (len(paths) + 1), 4))
    points = np.concatenate([p[:, :2] for p in paths.values()])
    low, high = points.min(axis=0), points.max(axis=0)
    margin = 0.05 * float(np.max(high - low))
    for index, (axis, (name, values)) in enumerate(zip(axes[:-1], paths.items(), strict=True)):
        axis.plot(values[:, 0], values[:, 1], color=f"C{index}", lw=0.8)
        axis.plot(values[0, 0], values[0, 1], "ko", ms=4)
        axis.set_xlim(low[0] - margin, high[0] + margin)
        axis.set_ylim(low[1] - margin, high[1] + margin)
        axis.set_aspect("equal")
        axis.set_title(name, fontsize=10)
        axis.set_xlabel("x (m)")
        axis.set_ylabel("y (m)")
        axis.grid(alpha=0.3)
    bars = axes[-1]
    keys = ("success", "coverage", "jerk_ratio")
    width = 0.8 / max(len(summaries), 1)
    for index, (name, summary) in enumerate(summaries.items()):
        found = [summary["intervals"].get(key) for key in keys]
        heights = [np.nan if f is None else f["estimate"] for f in found]
        errors = np.array([[0.0, 0.0] if f is None else [f["estimate"] - f["low"], f["high"] - f["estimate"]]
                           for f in found]).T
        bars.bar(np.arange(len(keys)) + index * width, heights, width, yerr=errors, capsize=3, label=name,
                 color=f"C{index}")
    bars.set_xticks(np.arange(len(keys)) + 0.4 - width / 2, ["success rate", "coverage", "jerk / imitation"],
                    fontsize=8)
    bars.axhline(1.0, color="k", lw=0.6, ls=":")
    bars.grid(alpha=0.3, axis="y")
    bars.legend(fontsize=8)
    bars.set_title("test contexts: mean, 95 % CI", fontsize=10)
    figure.suptitle(title)
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)
