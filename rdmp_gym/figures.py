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
from .dmp import RhythmicDMP
from .plots import (
    plot_basis_activations,
    plot_canonical_system,
    plot_convergence,
    plot_generalisation,
    plot_multiple_transients,
    plot_reproductions,
)

__all__ = ["write_paper_figures"]

logger = logging.getLogger(__name__)

STYLE_NAMES = {1: "1: simple + circle", 2: "2: complex + circle", 3: "3: simple + eight", 4: "4: complex + eight"}


def _save(fig: plt.Figure, path: Path) -> Path:
    fig.savefig(path, dpi=110)
    plt.close(fig)
    logger.info("wrote %s", path)
    return path


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

    demo = demos[4]
    signal = Demonstration(demo.t, demo.Y[:, :1])
    fits = {n: RhythmicDMP.fit(signal, n, n).rollout(demo.t)[:, 0] for n in (10, 14, 20, 27, 35, 40)}
    written.append(_save(plot_convergence(demo.t - demo.t[0], demo.truth.clean[:, 0], fits),
                         out / "fig08_convergence.png"))

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
