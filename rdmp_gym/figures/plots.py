"""Figures in the style of the paper (matplotlib; each function returns a ``Figure``).

matplotlib is an optional extra (``pip install "rdmp-gym[plots]"``): it is imported when a figure is drawn, so
importing this module (or :mod:`rdmp_gym`) never loads it.
"""

from __future__ import annotations

from collections.abc import Sequence
from types import ModuleType
from typing import TYPE_CHECKING

import numpy as np

from ..dmp.canonical import CanonicalSystem
from ..dmp.rhythmic import RhythmicDMP
from ..signals.demonstrations import Demonstration

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = [
    "plot_basis_activations",
    "plot_canonical_system",
    "plot_convergence",
    "plot_generalisation",
    "plot_multiple_transients",
    "plot_reproductions",
    "pyplot",
]


def pyplot() -> ModuleType:
    """``matplotlib.pyplot``, imported on first use (the optional ``plots`` extra); a clear error without it."""
    try:
        import matplotlib.pyplot as plt  # optional extra: loaded only when a figure is drawn
    except ModuleNotFoundError as error:
        raise ModuleNotFoundError('the figures need matplotlib, the "plots" extra: pip install "rdmp-gym[plots]"',
                                  name=error.name) from error
    return plt


def plot_canonical_system(canonical: CanonicalSystem, starts: Sequence[tuple[float, float]],
                          duration: float = 4.0) -> Figure:
    """Fig. 2: phase-plane paths and r(t) from several initial conditions ``(phi0, r0)``."""
    plt = pyplot()
    t = np.linspace(0.0, duration, 2000)
    fig, (plane, radius) = plt.subplots(1, 2, figsize=(10, 4.5))
    for phi0, r0 in starts:
        phi, r = canonical.state(t, phi0, r0)
        plane.plot(r * np.cos(phi), r * np.sin(phi), lw=1, label=f"r0 = {r0:g}")
        plane.plot(r0 * np.cos(phi0), r0 * np.sin(phi0), "ko", ms=3)
        radius.plot(t, r, lw=1.5, label=f"r0 = {r0:g}")
    circle = np.linspace(0, 2 * np.pi, 200)
    plane.plot(canonical.mu * np.cos(circle), canonical.mu * np.sin(circle), "k--", lw=1, label="limit cycle")
    plane.set(aspect="equal", xlabel="r cos(phi)", ylabel="r sin(phi)", title="Phase plane")
    radius.set(xlabel="t [s]", ylabel="r", title="Radius", yscale="log")
    radius.axhline(canonical.mu, color="k", ls="--", lw=1)
    radius.legend(fontsize=8)
    fig.tight_layout()
    return fig


def plot_basis_activations(dmp: RhythmicDMP, duration: float, transient: int = 0) -> Figure:
    """Fig. 6: every basis function's raw activation over time along one transient's path."""
    plt = pyplot()
    start = dmp.transients[transient]
    t = np.linspace(0.0, duration, 3000)
    phi, r = dmp.canonical.state(t, start.phi0, start.r0)
    activation = dmp.basis.activations(phi, r)
    n = dmp.basis.n_periodic
    fig, ax = plt.subplots(figsize=(10, 4))
    ax.plot(t, activation[:, n:], color="tab:red", lw=0.8)
    ax.plot(t, activation[:, :n], color="tab:blue", lw=0.8)
    ax.axvline(start.length, color="k", ls="--", lw=1, label="transient length T")
    fading_start = start.length - dmp.canonical.time_between(dmp.basis.fading.mu2, dmp.basis.fading.mu1)
    ax.axvspan(fading_start, start.length, color="0.9", label="fading")
    ax.plot([], [], color="tab:red", label="transient psi_j")
    ax.plot([], [], color="tab:blue", label="periodic phi_i")
    ax.set(xlabel="t [s]", ylabel="activation", title="Basis functions over time", ylim=(0, 1.05))
    ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    return fig


def plot_reproductions(demos: Sequence[Demonstration], reproductions: Sequence[np.ndarray],
                       titles: Sequence[str]) -> Figure:
    """Fig. 7: demonstrations (top) and DMP reproductions (bottom) in the table plane (dims 0, 1)."""
    plt = pyplot()
    fig, axes = plt.subplots(2, len(demos), figsize=(3.2 * len(demos), 6.4), squeeze=False)
    for column, (demo, Y, title) in enumerate(zip(demos, reproductions, titles, strict=True)):
        for row, (data, label) in enumerate(((demo.Y, "demonstration"), (Y, "reproduction"))):
            ax = axes[row, column]
            ax.plot(data[:, 0], data[:, 1], lw=0.8, color="tab:blue" if row == 0 else "tab:green")
            ax.plot(data[0, 0], data[0, 1], "ko", ms=4)
            ax.set(aspect="equal", title=f"{title}\n{label}", xlabel="x [m]", ylabel="y [m]")
    fig.tight_layout()
    return fig


def plot_convergence(t: np.ndarray, signal: np.ndarray, fits: dict[int, np.ndarray]) -> Figure:
    """Fig. 8: a 1-D signal (thick) and reproductions for increasing N = M (thin)."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(10, 4))
    ax.plot(t, signal, color="k", lw=3, label="signal")
    for n, Y in fits.items():
        ax.plot(t, Y, lw=1, label=f"N = M = {n}")
    ax.set(xlabel="t [s]", ylabel="y", title="Convergence with the number of basis functions")
    ax.legend(fontsize=8, ncol=4)
    fig.tight_layout()
    return fig


def plot_generalisation(dmp: RhythmicDMP, t: np.ndarray, anchors: np.ndarray, starts: np.ndarray) -> Figure:
    """Fig. 9: reproductions for new anchors (left, dots) and new starts (right) in the table plane."""
    plt = pyplot()
    original = dmp.rollout(t)
    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4.8))
    for ax, title in ((left, "New anchor points"), (right, "New start points")):
        ax.plot(original[:, 0], original[:, 1], "k", lw=1.5, label="original")
        ax.set(aspect="equal", xlabel="x [m]", ylabel="y [m]", title=title)
    for anchor in anchors:
        Y = dmp.rollout(t, anchor=anchor)
        left.plot(Y[:, 0], Y[:, 1], "--", lw=1)
        left.plot(anchor[0], anchor[1], "ko", ms=4)
    for start in starts:
        Y = dmp.rollout(t, y0=start)
        right.plot(Y[:, 0], Y[:, 1], "--", lw=1)
        right.plot(start[0], start[1], "ko", ms=4)
    left.legend(fontsize=8)
    fig.tight_layout()
    return fig


def plot_multiple_transients(dmp: RhythmicDMP, demos: Sequence[Demonstration], dim: int = 0) -> Figure:
    """Fig. 12: K demonstrations (solid) sharing one pattern and their reproductions (dashed), one dimension."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(10, 4))
    for k, demo in enumerate(demos):
        t = demo.t - demo.t[0]
        line = ax.plot(t, demo.Y[:, dim], lw=2, alpha=0.5, label=f"demonstration {k + 1}")[0]
        ax.plot(t, dmp.rollout(demo.t, transient=k)[:, dim], "--", color=line.get_color(), lw=1.2,
                label=f"reproduction {k + 1}")
        ax.axvline(dmp.transients[k].length, color=line.get_color(), lw=1)
    ax.set(xlabel="t [s]", ylabel=f"y[{dim}] [m]", title="Three transients into one periodic pattern")
    ax.legend(fontsize=8, ncol=3)
    fig.tight_layout()
    return fig
