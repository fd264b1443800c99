"""Segmentation of a whole recording: the rhythm under a large discrete motion, where it starts and ends, and the
rests before and after it.

A person's recording is slow motion (rest, approach, drift of the working point, departure, rest) with a rhythm
on top of it for part of the time. Method:

1. Period. Of candidate periods, the shortest that explains most of the motion beyond local polynomials gives a
   coarse period (:func:`~rdmp_gym.signals.segmentation.period.estimate_period`, method ``"local_fit"``); the Fourier
   fit of the full-size rhythm refines it (:func:`~rdmp_gym.signals.segmentation.period.refine_period`).
2. Slow part and envelope. Around every point (windows of two periods) a cubic polynomial plus a Fourier series
   of the period is fitted by least squares (:func:`~rdmp_gym.signals.segmentation.fourier.local_fit`): the polynomial
   at the centre is the slow part (the working point), the size of the harmonics is the rhythm's local amplitude.
   Unlike a moving average, the polynomial follows an accelerating approach without smearing it into the rhythm.
3. Change points. The rhythm runs at full size from where the envelope first reaches ``full`` of its typical
   level until it last does, or until the working point departs (the slow part's speed exceeds a quarter of the
   rhythm's); it starts to grow where the envelope first exceeds ``begin`` of that level.
4. Where a person would mark it. The rhythm's onset and stop: the first and last stroke on the working surface
   (the plane of the full-size rhythm; :mod:`rdmp_gym.signals.segmentation.onset`), earlier and later than the full-size
   rhythm by the first and last strokes. Reported beside it; the fit uses the full-size rhythm.
5. Rest. Speed below ``rest_fraction`` of the rhythm's typical speed (:mod:`rdmp_gym.signals.segmentation.rest`): the
   hand leaves its first rest at the first faster sample and is at rest after the rhythm from the first sample
   after which it stays slower. Relative to the motion's own scale, so a slow drift and sensor noise at rest pass.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from rdmp_gym.signals.demonstrations import Demonstration
from rdmp_gym.signals.filters import longest_run
from rdmp_gym.validation import as_finite_array, check_positive

from .fourier import local_fit
from .onset import rhythm_bounds
from .period import estimate_period, refine_period
from .rest import high_level, motion_speed, rest_onset, rest_threshold

__all__ = ["RhythmSegmentation", "segment_rhythm"]

logger = logging.getLogger(__name__)

_DEPARTURE_SPEED = 0.25     # share of the rhythm's speed at which the working point's motion is a departure


@dataclass(frozen=True, eq=False)
class RhythmSegmentation:
    """Result of :func:`segment_rhythm` (times from ``demo.t[0]``, s).

    Attributes:
        period: mean period of the rhythm.
        onset: the hand leaves its first rest (0 if it moves from the first sample).
        entry: the rhythm starts to grow.
        rhythm_start: the rhythm runs at full size from here.
        rhythm_end: ... until here.
        rhythm_onset: the first stroke on the working surface (:mod:`.onset`).
        rhythm_stop: ... and the last one.
        rest_time: at rest from here to the end; ``None`` if the recording does not end at rest.
        slow: ``[L, d]`` the slow part of the motion (the working point) at every sample.
        amplitude: ``[L]`` the rhythm's local amplitude (m, root of the summed squared harmonics).
        rest_speed: the speed below which the hand counts as at rest (m/s).
    """

    period: float
    onset: float
    entry: float
    rhythm_start: float
    rhythm_end: float
    rhythm_onset: float
    rhythm_stop: float
    rest_time: float | None
    slow: np.ndarray
    amplitude: np.ndarray
    rest_speed: float


def segment_rhythm(demo: Demonstration, *, period: float | None = None, start: float | None = None,
                   end: float | None = None, begin: float = 0.15, full: float = 0.75,
                   rest_fraction: float = 0.05, min_periods: float = 2.0) -> RhythmSegmentation:
    """Find the rhythm in a whole recording and the rests around it (see the module docstring).

    Args:
        demo: the recording on an even grid (outliers removed, e.g.
            :func:`rdmp_gym.signals.demonstrations.to_demonstration`).
        period: the known period (s); estimated when ``None``.
        start, end: the known start and end of the full-size rhythm (s from ``demo.t[0]``); detected when ``None``.
        begin, full: shares of the rhythm's typical amplitude at which it starts to grow and is full-size.
        rest_fraction: share of the rhythm's typical speed below which the hand is at rest.
        min_periods: the fewest periods the full-size rhythm must span.
    Raises:
        ValueError: no rhythm, fewer than ``min_periods`` periods, or a hint outside the recording.
    """
    if not isinstance(demo, Demonstration):
        raise TypeError(f"demo: expected a Demonstration, got {type(demo).__name__}")
    if not 0.0 < begin < full < 1.0:
        raise ValueError(f"begin, full: expected 0 < begin < full < 1, got {begin!r}, {full!r}")
    rest_fraction = check_positive(rest_fraction, "rest_fraction")
    t = demo.t - demo.t[0]
    for name, value in (("start", start), ("end", end)):
        if value is not None and not 0.0 <= float(as_finite_array(value, name, ndim=0)) <= t[-1]:
            raise ValueError(f"{name}: expected a time within the recording [0, {t[-1]:.4g}] s, got {value!r}")
    if start is not None and end is not None and not end > start:
        raise ValueError(f"end: expected a time after start={start!r}, got {end!r}")
    estimate = estimate_period(demo, "local_fit") if period is None else check_positive(period, "period")
    slow, amplitude = local_fit(demo, estimate)
    first, last = _rhythm_bounds(t, amplitude, full, start, end)
    if period is None:      # refine on the full-size rhythm, then fit again with the refined period
        Z = demo.Y[first:last + 1] - slow[first:last + 1]
        estimate = refine_period(t[first:last + 1], Z / np.maximum(np.std(Z, axis=0), 1e-12), estimate, demo.dt,
                                  12, 0.1)
        slow, amplitude = local_fit(demo, estimate)
        first, last = _rhythm_bounds(t, amplitude, full, start, end)
    if (t[last] - t[first]) / estimate < min_periods:
        raise ValueError(f"demo: the rhythm spans only {(t[last] - t[first]) / estimate:.1f} periods "
                         f"({t[first]:.3g} s to {t[last]:.3g} s), need at least {min_periods:g}")
    speed = motion_speed(demo)
    if start is None:
        first = _arrival(slow, speed, first, last, demo.dt)
    level = high_level(amplitude[first:last + 1])
    growing = np.flatnonzero(amplitude[:first + 1] < begin * level)
    entry = int(growing[-1]) if growing.size else first
    if end is None:
        last = _departure(slow, speed, first, last, demo.dt)
    threshold = rest_threshold(speed, demo.dt, float(np.median(speed[first:last + 1])), rest_fraction)
    moving = np.flatnonzero(speed[:entry + 1] >= threshold)
    onset = int(moving[0]) if moving.size else entry
    rhythm_onset, rhythm_stop = rhythm_bounds(demo.Y, first, last, estimate, demo.dt)
    rest = rest_onset(speed, threshold, demo.dt)
    rest_time = None if rest is None or rest <= last else float(t[rest])
    logger.debug("segment_rhythm %r: period %.4f s, onset %.2f, entry %.2f, rhythm %.2f-%.2f s, rest %s",
                 demo.name, estimate, t[onset], t[entry], t[first], t[last], rest_time)
    return RhythmSegmentation(period=float(estimate), onset=float(t[onset]), entry=float(t[entry]),
                              rhythm_start=float(t[first]), rhythm_end=float(t[last]),
                              rhythm_onset=float(t[rhythm_onset]), rhythm_stop=float(t[rhythm_stop]),
                              rest_time=rest_time,
                              slow=slow, amplitude=amplitude, rest_speed=threshold)


def _working_point_moves(slow: np.ndarray, speed: np.ndarray, first: int, last: int, dt: float) -> np.ndarray:
    """``[T]`` whether the working point (the slow part) moves faster than ``_DEPARTURE_SPEED`` of the hand's
    typical speed in the rhythm ``[first, last]`` and three times its own typical speed there (a pattern that
    travels is not a departure)."""
    slow_speed = np.linalg.norm(np.gradient(slow, dt, axis=0), axis=1)
    rhythm = slice(first, last + 1)
    limit = max(_DEPARTURE_SPEED * float(np.median(speed[rhythm])), 3.0 * float(np.median(slow_speed[rhythm])))
    return slow_speed > limit


def _departure(slow: np.ndarray, speed: np.ndarray, first: int, last: int, dt: float) -> int:
    """The end of the rhythm ``[first, last]``, moved earlier to where its working point departs (first moves,
    :func:`_working_point_moves`, in the rhythm's second half). A departure about as long as a period looks
    rhythmic to the local fits, which then see the rhythm end late."""
    middle = (first + last) // 2
    leaving = np.flatnonzero(_working_point_moves(slow, speed, first, last, dt)[middle:last + 1])
    return middle + int(leaving[0]) if leaving.size else last


def _arrival(slow: np.ndarray, speed: np.ndarray, first: int, last: int, dt: float) -> int:
    """The start of the rhythm ``[first, last]``, moved later to where its working point has arrived (after its
    last move, :func:`_working_point_moves`, in the rhythm's first half). An approach shorter than a period looks
    rhythmic to the local fits, which then see the rhythm start with the approach."""
    middle = (first + last) // 2
    arriving = np.flatnonzero(_working_point_moves(slow, speed, first, last, dt)[first:middle + 1])
    return first + int(arriving[-1]) + 1 if arriving.size else first


def _rhythm_bounds(t: np.ndarray, amplitude: np.ndarray, full: float, start: float | None,
                   end: float | None) -> tuple[int, int]:
    """Indices of the first and last sample of the full-size rhythm: the longest run where the amplitude is at
    least ``full`` of its high level (or the given ``start``/``end``, s)."""
    level = high_level(amplitude)
    low, high = longest_run(amplitude >= full * level)
    if high == 0:
        raise ValueError("demo: no rhythm found (its amplitude never reaches its typical level)")
    first = low if start is None else int(np.searchsorted(t, start))
    last = high - 1 if end is None else int(min(np.searchsorted(t, end), t.size - 1))
    return first, last
