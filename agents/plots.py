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

__all__ = ["COMPARED", "logged_metrics", "plot_fit", "plot_learning_curve", "plot_policy_comparison",
           "plot_recording_fit"]


def _column(records: Sequence[dict[str, Any]], key: str) -> np.ndarray:
    return np.array([np.nan if r.get(key) is None else r[key] for r in records], dtype=np.float64)


#: the validation numbers of a log line that are the loop's own, not the task's metrics
_OWN_EVAL = ("episodes", "return_mean", "return_best", "success", "valid")


def logged_metrics(records: Sequence[dict[str, Any]]) -> list[tuple[str, str]]:
    """``(key, label)`` of the task's metrics a log holds: its ``eval_<key>`` columns other than the loop's own, in
    the order they first appear, labelled by their keys."""
    keys = dict.fromkeys(key[5:] for record in records for key in record if key.startswith("eval_"))
    return [(key, key.replace("_", " ")) for key in keys if key not in _OWN_EVAL]


def plot_learning_curve(records: Sequence[dict[str, Any]], path: str | Path, title: str = "",
                        metrics: Sequence[tuple[str, str]] | None = None) -> None:
    """The return, the success rate (where the env reports success) and the task's metrics of the policy on the
    validation contexts (and of the rollouts) against training episodes, from the log ``records``; ``metrics``:
    ``(key, label)`` of the task's metrics (None: the ``eval_*`` columns of the log that are not the loop's own)."""
    episodes = _column(records, "episodes")
    chosen = logged_metrics(records) if metrics is None else list(metrics)
    panels = [("return", "eval_return_mean", "return_mean"), ("success rate", "eval_success", "success"),
              *((label, f"eval_{key}", key) for key, label in chosen)]
    panels = [p for p in panels if np.any(np.isfinite(_column(records, p[1])))]
    figure, axes = plt.subplots(1, max(len(panels), 1), figsize=(4.2 * max(len(panels), 1), 3.4), squeeze=False)
    for axis, (label, policy_key, rollout_key) in zip(axes[0], panels, strict=False):
        values = _column(records, policy_key)
        shown = np.isfinite(values)      # the policy is evaluated every eval_every updates
        axis.plot(episodes[shown], values[shown], "o-", ms=3, label="policy (validation contexts)")
        axis.plot(episodes, _column(records, rollout_key), ".", alpha=0.6, label="rollouts (mean)")
        if label == "return":
            axis.plot(episodes, _column(records, "return_best"), "x", ms=3, alpha=0.5, label="rollouts (best)")
        axis.set_xlabel("training episodes")
        axis.set_ylabel(label)
        axis.grid(alpha=0.3)
    if panels:
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


def _draw_path(axis: Any, values: np.ndarray, colour: str, labels: Sequence[str], dt: float,
               limits: tuple[np.ndarray, np.ndarray]) -> None:
    """One policy's path ``[T, 1]`` against time (``dt`` s per step) or ``[T, 2]``, one column against the other;
    ``labels``: the columns' names; ``limits``: their (low, high), shared by every policy's panel."""
    low, high = limits
    margin = 0.05 * float(np.max(high - low)) or 1e-3
    if values.shape[1] == 1:
        axis.plot(dt * np.arange(len(values)), values[:, 0], color=colour, lw=0.8)
        axis.set_ylim(low[0] - margin, high[0] + margin)
        axis.set_xlabel("t (s)")
        axis.set_ylabel(labels[0])
        return
    axis.plot(values[:, 0], values[:, 1], color=colour, lw=0.8)
    axis.plot(values[0, 0], values[0, 1], "ko", ms=4)
    axis.set_xlim(low[0] - margin, high[0] + margin)
    axis.set_ylim(low[1] - margin, high[1] + margin)
    axis.set_aspect("equal")
    axis.set_xlabel(labels[0])
    axis.set_ylabel(labels[1])


def _drawn_columns(paths: Sequence[np.ndarray]) -> list[int]:
    """The (at most two) columns of the paths ``[T, d]`` that move the most over all of them, in column order."""
    spread = np.nanmax([np.ptp(values, axis=0) for values in paths], axis=0)
    return sorted(int(i) for i in np.argsort(-spread, kind="stable")[:2])


#: what :func:`plot_policy_comparison` shows below the paths by default: ``(interval key, label)``
COMPARED = (("success", "success rate"), ("jerk_ratio", "jerk / imitation"))


def plot_policy_comparison(paths: dict[str, np.ndarray], summaries: dict[str, dict[str, Any]], path: str | Path,
                           title: str = "", quantities: Sequence[tuple[str, str]] = COMPARED,
                           labels: Sequence[str] = ("x", "y", "z"), dt: float = 1.0) -> None:
    """The executed paths ``[T]`` or ``[T, d]`` of named policies side by side on the same axes (``d >= 2``: the two
    columns that move the most, one against the other, named by ``labels``; one column: against time, ``dt`` s per
    step), and below them one panel per quantity ``(key, label)`` with each policy's mean and 95 % interval
    (``summaries[name]["intervals"][key]``; a quantity no policy has is left out)."""
    paths = {name: np.asarray(values, dtype=np.float64).reshape(len(values), -1) for name, values in paths.items()}
    if not paths or len({values.shape[1] for values in paths.values()}) != 1:
        raise ValueError(f"paths: expected paths [T] or [T, d] of one d, got shapes "
                         f"{[values.shape for values in paths.values()]}")
    columns = _drawn_columns(list(paths.values()))
    names = [labels[i] if i < len(labels) else str(i) for i in columns]
    paths = {name: values[:, columns] for name, values in paths.items()}
    drawn = np.concatenate(list(paths.values()))
    limits = (np.nanmin(drawn, axis=0), np.nanmax(drawn, axis=0))
    shown = [(key, label) for key, label in quantities
             if any(summary["intervals"].get(key) is not None for summary in summaries.values())]
    figure = plt.figure(figsize=(4.2 * max(len(paths), len(shown), 1), 7.6))
    top, bottom = figure.subfigures(2, 1, height_ratios=(1.1, 1.0))
    path_axes = top.subplots(1, max(len(paths), 1), squeeze=False)[0]
    for index, (axis, (name, values)) in enumerate(zip(path_axes, paths.items(), strict=False)):
        _draw_path(axis, values, f"C{index}", names, dt, limits)
        axis.set_title(name, fontsize=10)
        axis.grid(alpha=0.3)
    bar_axes = bottom.subplots(1, max(len(shown), 1), squeeze=False)[0]
    for axis, (key, label) in zip(bar_axes, shown, strict=False):
        for index, summary in enumerate(summaries.values()):
            found = summary["intervals"].get(key)
            if found is not None:
                error = [[found["estimate"] - found["low"]], [found["high"] - found["estimate"]]]
                axis.bar(index, found["estimate"], 0.7, yerr=error, capsize=3, color=f"C{index}")
        axis.set_xticks(range(len(summaries)), list(summaries), fontsize=8)
        axis.set_title(label, fontsize=10)
        axis.grid(alpha=0.3, axis="y")
        if key == "jerk_ratio":
            axis.axhline(1.0, color="k", lw=0.6, ls=":")
    figure.suptitle(f"{title}\n(below: the test contexts' mean with its 95 % CI)" if title
                    else "the test contexts' mean with its 95 % CI", fontsize=10)
    figure.savefig(path, dpi=110)
    plt.close(figure)
