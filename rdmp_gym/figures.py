"""Write the paper's figures (2, 6, 7, 8, 9, 12) for the built-in demonstrations as PNG files.

Run ``python -m rdmp_gym.figures --out figures/``.
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from .canonical import CanonicalSystem
from .demonstrations import Demonstration, multi_transient_demonstrations, wiping_demonstration
from .dmp import PAPER_SETTINGS, RhythmicDMP
from .plots import (
    plot_basis_activations,
    plot_canonical_system,
    plot_generalisation,
    plot_multiple_transients,
    plot_reproductions,
)
from .smoothness import finite_derivatives

__all__ = ["write_paper_figures"]

logger = logging.getLogger(__name__)

STYLE_NAMES = {1: "1: simple + circle", 2: "2: complex + circle", 3: "3: simple + eight", 4: "4: complex + eight"}


def _save(fig: plt.Figure, path: Path) -> Path:
    fig.savefig(path, dpi=110)
    plt.close(fig)
    logger.info("wrote %s", path)
    return path


def _convergence_figure(demo: Demonstration) -> plt.Figure:
    """Fig. 8 with what a robot executes: position (the paper's plot) and acceleration at 1 kHz of the x
    coordinate for N = M = 10 ... 40, the defaults beside the paper's settings at N = M = 40."""
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
    written = [_save(plot_canonical_system(CanonicalSystem(period=1.0), [(0.0, 0.2), (np.pi / 2, 0.6),
                                                                        (np.pi, 3.0), (1.5 * np.pi, 8.5)]),
                     out / "fig02_canonical.png")]

    demos = {style: wiping_demonstration(style, rng=seed + style) for style in STYLE_NAMES}
    dmps = {style: RhythmicDMP.fit(demo) for style, demo in demos.items()}

    # Fig. 6 as in the paper: M = 15, N = 30, period twice the transient length.
    fig6 = RhythmicDMP.fit(demos[1], n_periodic=30, n_transient=15)
    written.append(_save(plot_basis_activations(fig6, duration=fig6.transients[0].length + 2 * fig6.period),
                         out / "fig06_basis.png"))

    written.append(_save(plot_reproductions(list(demos.values()),
                                            [dmps[s].rollout(demos[s].t) for s in STYLE_NAMES],
                                            list(STYLE_NAMES.values())), out / "fig07_styles.png"))

    written.append(_save(_convergence_figure(demos[4]), out / "fig08_convergence.png"))

    dmp = dmps[1]
    offsets = np.array([[0.08, 0.05, 0.0], [-0.05, -0.08, 0.0], [0.1, -0.06, 0.0]])
    start_offsets = np.array([[0.05, -0.1, 0.0], [-0.05, 0.05, 0.02], [0.2, 0.05, 0.0]])
    written.append(_save(plot_generalisation(dmp, demos[1].t, dmp.anchor + offsets, dmp.starts[0] + start_offsets),
                         out / "fig09_generalisation.png"))

    multi = multi_transient_demonstrations(3, rng=seed)
    written.append(_save(plot_multiple_transients(RhythmicDMP.fit(multi, n_transient=30), multi),
                         out / "fig12_transients.png"))
    return written


def main(argv: list[str] | None = None) -> None:
    """Command-line entry: ``python -m rdmp_gym.figures --out DIR``."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="figures", help="output folder (default: figures)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the built-in demonstrations")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    for path in write_paper_figures(args.out, args.seed):
        print(path)


if __name__ == "__main__":
    main()
