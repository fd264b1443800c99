"""Imitation: demonstrations (built-in styles or a user's CSV/NPZ file) in, a fitted ``RhythmicDMP`` out.

The envs fit their DMP to the demonstration (their ``style`` or ``demonstration`` keyword) and map the
fit to ``a = 0``, the start of every learner; ``TaskSpec(demo=path)`` hands a user's file to them.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from rdmp_gym import Demonstration, RhythmicDMP, wiping_demonstration

__all__ = ["fit_dmp", "load_demonstration"]

logger = logging.getLogger(__name__)


def load_demonstration(source: int | str | Path, time_column: str = "t", rate: float | None = None
                       ) -> Demonstration:
    """A built-in wiping style (int 1-4, seed 0) or a ``.csv`` / ``.npz`` file (see ``Demonstration``).

    ``time_column`` names a CSV's time column; ``rate`` (Hz) resamples a file onto an even grid (uneven time
    stamps or another rate; ``Demonstration.from_samples``).
    """
    if isinstance(source, (int, np.integer)) and not isinstance(source, bool):
        return wiping_demonstration(int(source), rng=0)
    path = Path(source)
    if not path.exists():
        raise FileNotFoundError(f"demo: no such file {path}")
    if path.suffix.lower() == ".csv":
        return Demonstration.from_csv(path, time_column=time_column, rate=rate)
    if path.suffix.lower() == ".npz":
        demo = Demonstration.from_npz(path)
        return demo if rate is None else demo.resample(rate)
    raise ValueError(f"demo: expected a .csv or .npz file, got {path.name!r}")


def fit_dmp(demo: Demonstration, n_periodic: int, n_transient: int, method: str = "ridge") -> RhythmicDMP:
    """Fit a one-transient ``RhythmicDMP`` to ``demo`` (``[L, d]`` samples)."""
    dmp = RhythmicDMP.fit(demo, n_periodic=n_periodic, n_transient=n_transient, method=method)
    logger.info("fitted %s to %r", dmp, demo.name)
    return dmp
