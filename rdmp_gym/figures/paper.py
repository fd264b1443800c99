"""Write the paper's figures (2, 6, 7, 8, 9, 12) for the built-in demonstrations as PNG files.

Run ``python -m rdmp_gym.figures --out figures/`` (needs matplotlib, the ``plots`` extra). Everything here is the core
alone; the figures that need the MuJoCo environment are in ``benchmarks/env_figures.py``.
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..dmp.canonical import CanonicalSystem
from ..dmp.ending import plan_stop
from ..dmp.frequency import follow_rhythm
from ..dmp.rhythmic import PAPER_SETTINGS, RhythmicDMP
from ..dmp.stopping import fit_ending
from ..signals.demonstrations import Demonstration
from ..synthetic.demonstrations import ending_demonstration, multi_transient_demonstrations, wiping_demonstration
from ..synthetic.smoothness import finite_derivatives
from .plots import (
    plot_basis_activations,
    plot_canonical_system,
    plot_generalisation,
    plot_multiple_transients,
    plot_reproductions,
    pyplot,
)

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["BEYOND_PAPER_FIGURES", "save_figure", "write_paper_figures", "write_rhythm_figure", "write_stop_figure"]

logger = logging.getLogger(__name__)

STYLE_NAMES = {1: "1: simple + circle", 2: "2: complex + circle", 3: "3: simple + eight", 4: "4: complex + eight"}


def save_figure(fig: Figure, path: Path) -> Path:
    """Write ``fig`` to ``path`` (110 dpi), close it and log the path."""
    fig.savefig(path, dpi=110)
    pyplot().close(fig)
    logger.info("wrote %s", path)
    return path


def _convergence_figure(demo: Demonstration) -> Figure:
    """Fig. 8 with what a robot executes: position (the paper's plot) and acceleration at 1 kHz of the x
    coordinate for N = M = 10 ... 40, the defaults beside the paper's settings at N = M = 40."""
    plt = pyplot()
    signal = Demonstration(demo.t, demo.Y[:, :1])
    fine = wiping_demonstration(4, rng=0, rate=1000, noise=0.0)
    t = fine.t
    truth = fine.truth.clean[:, :1]
    _, truth_acceleration, _ = finite_derivatives(truth, t[1] - t[0])
    fits = {f"N = M = {n}": RhythmicDMP.fit(signal, n, n).rollout(t) for n in (10, 14, 20, 27, 35, 40)}
    fits["paper settings, 40"] = RhythmicDMP.fit(signal, **{**PAPER_SETTINGS, "method": "ridge"}).rollout(
        t, start_blend=False)
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(10, 7), sharex=True)
    top.plot(t, truth[:, 0], color="k", lw=3, label="signal")
    inner = slice(2, -2)                       # the one-sided differences at the two ends are not shown
    bottom.plot(t[inner], truth_acceleration[inner, 0], color="k", lw=3, label="signal")
    for label, Y in fits.items():
        style = dict(lw=0.8, ls=":", color="tab:red") if label.startswith("paper") else dict(lw=1)
        top.plot(t, Y[:, 0], label=label, **style)
        bottom.plot(t[inner], finite_derivatives(Y, t[1] - t[0])[1][inner, 0], label=label, **style)
    top.set(ylabel="x [m]", title="Convergence with the number of basis functions (style 4, x)")
    limit = 1.8 * np.abs(truth_acceleration).max()
    bottom.set(xlabel="t [s]", ylabel="acceleration [m/s²]", ylim=(-limit, limit))
    top.legend(fontsize=8, ncol=4)
    fig.tight_layout()
    return fig


def write_paper_figures(out_dir: str | Path, seed: int = 0) -> list[Path]:
    """Fit the built-in demonstrations and write ``fig02_canonical.png`` ... ``fig12_transients.png``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    canonical_starts = [(0.0, 0.2), (np.pi / 2, 0.6), (np.pi, 3.0), (1.5 * np.pi, 8.5)]
    written = [save_figure(plot_canonical_system(CanonicalSystem(period=1.0), canonical_starts),
                           out / "fig02_canonical.png")]

    demos = {style: wiping_demonstration(style, rng=seed + style) for style in STYLE_NAMES}
    dmps = {style: RhythmicDMP.fit(demo) for style, demo in demos.items()}

    # Fig. 6 as in the paper: M = 15, N = 30, period twice the transient length.
    fig6 = RhythmicDMP.fit(demos[1], n_periodic=30, n_transient=15)
    written.append(save_figure(plot_basis_activations(fig6, duration=fig6.transients[0].length + 2 * fig6.period),
                               out / "fig06_basis.png"))

    written.append(save_figure(plot_reproductions(list(demos.values()),
                                                  [dmps[s].rollout(demos[s].t) for s in STYLE_NAMES],
                                                  list(STYLE_NAMES.values())), out / "fig07_styles.png"))

    written.append(save_figure(_convergence_figure(demos[4]), out / "fig08_convergence.png"))

    dmp = dmps[1]
    offsets = np.array([[0.08, 0.05, 0.0], [-0.05, -0.08, 0.0], [0.1, -0.06, 0.0]])
    start_offsets = np.array([[0.05, -0.1, 0.0], [-0.05, 0.05, 0.02], [0.2, 0.05, 0.0]])
    figure = plot_generalisation(dmp, demos[1].t, dmp.anchor + offsets, dmp.starts[0] + start_offsets)
    written.append(save_figure(figure, out / "fig09_generalisation.png"))

    multi = multi_transient_demonstrations(3, rng=seed)
    written.append(save_figure(plot_multiple_transients(RhythmicDMP.fit(multi, n_transient=30), multi),
                               out / "fig12_transients.png"))
    return written


def write_stop_figure(out_dir: str | Path, seed: int = 0) -> Path:
    """``beyond_stop.png``: start, wiping and stop from one DMP, with its canonical path."""
    plt = pyplot()
    demo = ending_demonstration(1, rng=seed)
    dmp = fit_ending(demo)
    t = np.arange(0.0, demo.t[-1] + 1.0, 1e-3)
    request = 5.5
    stopped = dmp.rollout(t, stop_at=request)
    free = dmp.rollout(t)
    start = dmp.transients[0]
    plan = plan_stop(dmp.ending, request, start.phi0, dmp.canonical.omega, dmp.ending.goal[None])
    fig = plt.figure(figsize=(13, 7))
    grid = fig.add_gridspec(3, 3)
    for dim, label in enumerate("xyz"):
        ax = fig.add_subplot(grid[dim, :2])
        ax.plot(demo.t, demo.Y[:, dim], ".", color="0.6", ms=2, label="demonstration")
        ax.plot(t, free[:, dim], "--", color="tab:blue", lw=1, label="DMP, no stop")
        ax.plot(t, stopped[:, dim], color="tab:red", lw=1.5, label="DMP, stop requested")
        ax.axvline(request, color="k", lw=0.8, ls=":")
        ax.axvline(plan.exit_time, color="k", lw=0.8)
        ax.set_ylabel(f"{label} [m]")
        if dim == 0:
            ax.legend(fontsize=8, loc="upper left", ncol=3)
            ax.set_title("start, wiping and stop from one DMP (dotted: request, solid: exit at the demonstrated phase)")
    ax.set_xlabel("t [s]")
    plane = fig.add_subplot(grid[:2, 2])
    phi, r = dmp.canonical.state(t, start.phi0, start.r0)
    tau = t - plan.exit_time
    r_stop = np.where(tau >= 0, r * dmp.ending.radius_factor(tau), r)
    plane.plot(r_stop * np.cos(phi), r_stop * np.sin(phi), lw=1, color="tab:red")
    plane.plot(*dmp.ending.centres.T, "k.", ms=4, label="stop centres")
    plane.plot(*dmp.basis.transient_centres.T, "x", color="0.5", ms=3, label="start centres")
    plane.set(aspect="equal", xlim=(-2.5, 2.5), ylim=(-2.5, 2.5), title="canonical path: in, around, out")
    plane.legend(fontsize=7)
    top = fig.add_subplot(grid[2, 2])
    top.plot(demo.Y[:, 0], demo.Y[:, 1], ".", color="0.6", ms=2)
    top.plot(stopped[:, 0], stopped[:, 1], color="tab:red", lw=1)
    top.plot(*dmp.ending.goal[:2], "k*", ms=8)
    top.set(aspect="equal", xlabel="x [m]", ylabel="y [m]")
    fig.tight_layout()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    return save_figure(fig, out / "beyond_stop.png")


def write_rhythm_figure(out_dir: str | Path, seed: int = 0) -> Path:
    """``beyond_rhythm.png``: the DMP's frequency and phase lock onto a partner whose frequency steps by +-30 %."""
    plt = pyplot()
    dmp = RhythmicDMP.fit(wiping_demonstration(1, rng=seed))
    dt, step = 2e-3, 10.0
    t = np.arange(round(30.0 / dt)) * dt
    fig, axes = plt.subplots(3, 2, figsize=(13, 8))
    for column, factor in enumerate((1.3, 0.7)):
        omega = np.where(t < step, dmp.canonical.omega, factor * dmp.canonical.omega)
        psi = dmp.transients[0].phi0 + np.concatenate([[0.0], np.cumsum(omega[:-1]) * dt])
        u = (0.05 * np.cos(psi) + 0.01 * np.cos(2.0 * psi + 0.3)
             + 1e-3 * np.random.default_rng(seed).standard_normal(t.size))
        out = follow_rhythm(dmp, u, dt)
        fixed = dmp.transients[0].phi0 + dmp.canonical.omega * t
        axes[0, column].plot(t, omega, "k", lw=1, label="partner")
        axes[0, column].plot(t, out["oscillator"], color="0.7", lw=0.6, label="oscillator Omega_A")
        axes[0, column].plot(t, out["frequency"], "tab:red", lw=1.5, label="DMP (smoothed)")
        axes[0, column].set(ylabel="frequency [rad/s]", title=f"partner's frequency steps by {factor - 1:+.0%}")
        axes[1, column].plot(t, np.angle(np.exp(1j * (out["phase"] - psi))), "tab:red", lw=1, label="adaptive")
        axes[1, column].plot(t, np.angle(np.exp(1j * (fixed - psi))), "tab:blue", lw=1, ls="--", label="fixed")
        axes[1, column].set(ylabel="phase - partner [rad]", ylim=(-np.pi, np.pi))
        late = t > 24.0
        axes[2, column].plot(t[late], u[late], "k", lw=1, label="partner x")
        axes[2, column].plot(t[late], out["y"][late, 0], "tab:red", lw=1.5, label="DMP x (adaptive)")
        axes[2, column].plot(t[late], dmp.rollout(t)[late, 0], "tab:blue", lw=1, ls="--", label="DMP x (fixed)")
        axes[2, column].set(xlabel="t [s]", ylabel="x [m]")
        for ax in axes[:, column]:
            ax.axvline(step, color="k", lw=0.6, ls=":")
            ax.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    out_path = Path(out_dir)
    out_path.mkdir(parents=True, exist_ok=True)
    return save_figure(fig, out_path / "beyond_rhythm.png")


BEYOND_PAPER_FIGURES = [write_stop_figure, write_rhythm_figure]
"""Figures of what the paper leaves open (each ``(out_dir, seed) -> Path``); ``main`` writes them after the paper's.
The figures that need the MuJoCo environment (force learning, the cup) are written by ``benchmarks/env_figures.py``."""


def main(argv: list[str] | None = None) -> None:
    """Command-line entry: ``python -m rdmp_gym.figures --out DIR``."""
    parser = argparse.ArgumentParser(prog="python -m rdmp_gym.figures", description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="figures", help="output folder (default: figures)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the built-in demonstrations")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    for path in write_paper_figures(args.out, args.seed):
        print(path)
    for write in BEYOND_PAPER_FIGURES:
        path = write(args.out, args.seed)
        if path is not None:
            print(path)
