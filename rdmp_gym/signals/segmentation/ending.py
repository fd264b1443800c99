"""Segmentation of a demonstration that ends: the start transient, the periodic part, the stop and the final rest.

The start and the periodic part are found by :func:`~rdmp_gym.signals.segmentation.segment` on a head of the
demonstration that stops short of the ending; the final rest by the speed (:mod:`rdmp_gym.signals.segmentation.rest`);
the end of the periodic part is the change point of the residual against the periodic template read backwards
(:mod:`rdmp_gym.signals.segmentation.fourier`), the mirror of how the start is found. The stop's fit
(:func:`rdmp_gym.dmp.stopping.fit_ending`) reads the result.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from rdmp_gym.signals.demonstrations import Demonstration
from rdmp_gym.validation import check_positive

from .demonstration import Segmentation, segment
from .fourier import change_point, normalised, scaled_residual
from .rest import rest_start

__all__ = ["StopSegmentation", "segment_ending"]

logger = logging.getLogger(__name__)

_HEAD_SHARES = (2.0 / 3.0, 0.75, 0.85)
"""Shares of the time to rest tried, in order, as the part of the demonstration that :func:`segment` sees."""


@dataclass(frozen=True, eq=False)
class StopSegmentation:
    """Where a demonstration that ends leaves its periodic pattern and comes to rest.

    Attributes:
        start: the segmentation of the start and periodic part (:func:`rdmp_gym.segment`).
        periodic_end: time from ``demo.t[0]`` of the last sample that fits the periodic pattern (s).
        rest_time: time from ``demo.t[0]`` from which the demonstration is at rest (s).
        goal: ``[d]`` the rest position (mean over the rest).
    """

    start: Segmentation
    periodic_end: float
    rest_time: float
    goal: np.ndarray


def segment_ending(demo: Demonstration, *, period: float | None = None, rest_fraction: float = 0.05,
                   margin: float = 2.0, n_harmonics: int = 12) -> StopSegmentation:
    """Find the start transient, the periodic part, the stop and the rest in a demonstration that ends.

    Rest: the demonstration is at rest from the first sample after which its speed (smoothed,
    :func:`rdmp_gym.signals.segmentation.rest.motion_speed`) stays below ``rest_fraction`` of its typical speed while it
    moves (or three times its speed in its quietest 0.5 s, where that is higher: sensor noise), for at least 0.2 s;
    the goal is the mean position over the rest. Relative to the motion's own scale, so a slow drift at rest and
    sensor noise pass. Periodic part: :func:`rdmp_gym.segment` on
    the samples up to two thirds of the rest time (so the stop does not enter it; 3/4 or 0.85 of it when
    that shows too little of the periodic part); the Fourier template of the periodic
    part is then extended to the rest, and the end of the periodic part is the change point of its
    noise-scaled residual read backwards (the mirror of how :func:`segment` finds the start). Raises
    ``ValueError`` if the demonstration does not come to rest or shows too little periodic motion.
    """
    if not isinstance(demo, Demonstration):
        raise TypeError(f"demo: expected a Demonstration, got {type(demo).__name__}")
    rest_fraction = check_positive(rest_fraction, "rest_fraction")
    t, dt = demo.t - demo.t[0], demo.dt
    tail = max(round(0.2 / dt), 5)
    if demo.n_samples < 10 * tail:
        raise ValueError(f"demo: too short ({demo.duration:.3g} s) to hold a start, periods and a stop")
    rest_index = rest_start(demo, rest_fraction, min_rest=tail * dt)
    if rest_index is None:
        raise ValueError(f"demo: does not come to rest (its last {tail * dt:.2g} s move faster than "
                         f"{rest_fraction:.0%} of its typical speed)")
    goal = demo.Y[rest_index:].mean(axis=0)
    seg, head = None, 0
    for share in _HEAD_SHARES:       # the shortest head that shows the periodic part (less risk of the stop in it)
        head = round(share * rest_index)
        try:
            seg = segment(Demonstration(demo.t[:head], demo.Y[:head]), period=period, min_periods=1.0,
                          n_harmonics=n_harmonics, margin=margin)
            break
        except ValueError as error:
            reason = error
    if seg is None:
        raise ValueError(f"demo: no periodic part found before the stop ({reason})")
    first = round(seg.transient_length / dt)
    Z, _, _ = normalised(demo.Y[: rest_index + 1])
    scaled = scaled_residual(t[: rest_index + 1], Z, slice(first, head), seg.period, dt, n_harmonics)
    # read the part after the start transient backwards: the stop becomes a "transient"
    backwards = change_point(scaled[first:][::-1], margin)
    periodic_end = t[rest_index - backwards]
    if periodic_end <= t[head - 1] - 0.5 * seg.period:
        raise ValueError("demo: the periodic part ends too early to segment the stop")
    logger.debug("segment_ending %r: periodic until %.3f s, at rest from %.3f s", demo.name, periodic_end,
                 t[rest_index])
    return StopSegmentation(seg, float(periodic_end), float(t[rest_index]), goal)
