"""Segmentation of a whole recording: the rhythm under a large discrete motion, where it starts and ends, and the
rests before and after it.

A person's recording is slow motion (rest, approach, drift of the working point, departure, rest) with a rhythm
on top of it for part of the time. Method:

1. Period. The slow motion is removed with a high-pass filter; the rhythm is where the remaining signal is
   strong (its envelope above a third of its high level); the autocorrelation of that window gives a coarse
   period, which the Fourier fit of :mod:`rdmp_gym.segmentation` refines.
2. Slow part and envelope. Around every point (windows of two periods) a cubic polynomial plus a Fourier series
   of the period is fitted by least squares: the polynomial at the centre is the slow part (the working point),
   the size of the harmonics is the rhythm's local amplitude. Unlike a moving average, the polynomial follows an
   accelerating approach without smearing it into the rhythm.
3. Change points. The rhythm runs at full size from where the envelope first reaches ``full`` of its typical
   level until it last does, or until the working point departs (the slow part's speed exceeds a quarter of the
   rhythm's); it starts to grow where the envelope first exceeds ``begin`` of that level.
4. Rest. Speed (smoothed over ``_SPEED_WINDOW``) below ``rest_fraction`` of the rhythm's typical speed: the hand
   leaves its first rest at the first faster sample and is at rest after the rhythm from the first sample after
   which it stays slower. Relative to the motion's own scale, so a slow drift and sensor noise at rest pass.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import median_filter

from .demonstrations import Demonstration
from .fitting import smooth_derivatives
from .segmentation import _refine_period
from .validation import as_finite_array, check_positive

__all__ = ["RhythmSegmentation", "local_fit", "motion_speed", "rest_onset", "rest_start", "segment_rhythm"]

logger = logging.getLogger(__name__)

_CANDIDATES = np.geomspace(0.3, 4.0, 45)   # s: the periods the coarse search tries
_MIN_EXPLAINED = 0.2        # least share of the motion beyond a slow trend that the rhythm must explain
_SPEED_WINDOW = 0.5         # s: smoothing of the speed used for rest (Savitzky-Golay, then a median over 0.3 s)
_DEPARTURE_SPEED = 0.25     # share of the rhythm's speed at which the working point's motion is a departure
_NOISE_FACTOR = 3.0         # the rest threshold is at least this multiple of the speed in the quietest 0.5 s
_MIN_REST = 0.3             # s: the shortest final rest recognised
_N_HARMONICS = 4            # harmonics of the local Fourier fit
_DEGREE = 3                 # degree of the local polynomial
_STEP = 0.05                # s: spacing of the local fits (interpolated between)


@dataclass(frozen=True, eq=False)
class RhythmSegmentation:
    """Result of :func:`segment_rhythm` (times from ``demo.t[0]``, s).

    Attributes:
        period: mean period of the rhythm.
        onset: the hand leaves its first rest (0 if it moves from the first sample).
        entry: the rhythm starts to grow.
        rhythm_start: the rhythm runs at full size from here.
        rhythm_end: ... until here.
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
    rest_time: float | None
    slow: np.ndarray
    amplitude: np.ndarray
    rest_speed: float


def motion_speed(demo: Demonstration, window: float = _SPEED_WINDOW) -> np.ndarray:
    """Speed ``[L]`` (m/s, norm over the dimensions) of ``demo`` smoothed over ``window`` s (Savitzky-Golay; the
    first and last half window hold the nearest inner value), then the median over 0.3 s (a single bump of noise
    does not end a rest)."""
    speed = np.linalg.norm(smooth_derivatives(demo.Y, demo.dt, window, polyorder=3)[1], axis=1)
    edge = min(round(0.5 * window / demo.dt), (speed.size - 1) // 2)
    if edge > 0:        # the fitted polynomials' ends swing with the noise: the edges take the nearest inner value
        speed[:edge], speed[-edge:] = speed[edge], speed[-edge - 1]
    return median_filter(speed, size=max(round(0.3 / demo.dt) | 1, 3), mode="nearest")


def _noise_speed(speed: np.ndarray, dt: float) -> float:
    """The median speed over the quietest 0.5 s of ``speed [L]`` (the noise level, where the hand rests somewhere)."""
    width = max(round(0.5 / dt), 1)
    if speed.size <= width:
        return float(np.median(speed))
    return float(np.min(median_filter(speed, size=width, mode="nearest")))


def rest_onset(speed: np.ndarray, threshold: float, dt: float, min_rest: float = _MIN_REST) -> int | None:
    """Index from which ``speed [L]`` stays below ``threshold`` to the end, if that lasts ``min_rest`` s; else None."""
    moving = np.flatnonzero(speed >= threshold)
    first = 0 if moving.size == 0 else int(moving[-1]) + 1
    return first if (speed.size - first) * dt >= min_rest else None


def rest_start(demo: Demonstration, fraction: float = 0.05, min_rest: float = _MIN_REST) -> int | None:
    """Index from which ``demo`` rests to its end (at least ``min_rest`` s), or ``None``: its speed
    (:func:`motion_speed`) stays below ``fraction`` of its typical speed while moving (:func:`_high_level`), or
    ``_NOISE_FACTOR`` times its speed in its quietest 0.5 s where that is higher."""
    speed = motion_speed(demo)
    threshold = max(fraction * _high_level(speed), _NOISE_FACTOR * _noise_speed(speed, demo.dt))
    return rest_onset(speed, threshold, demo.dt, min_rest)


def _high_level(values: np.ndarray) -> float:
    """A robust high level of ``values``: the median of those above half the 98th percentile."""
    top = np.quantile(values, 0.98)
    return float(np.median(values[values >= 0.5 * top]))


def _coarse_period(demo: Demonstration) -> float:
    """Coarse period (s) of the rhythm in ``demo``: of the candidate periods (``_CANDIDATES``), the shortest local
    maximum of what the harmonics explain beyond the local polynomials (:func:`_local_fit`) that reaches half the
    most any candidate explains (a fraction of the period explains little; a multiple explains as much, and more
    of the slow motion that its longer windows leave to the harmonics)."""
    scores = np.array([_local_fit(demo, candidate, candidate)[2] for candidate in _CANDIDATES])
    fast = demo.Y - smooth_derivatives(demo.Y, demo.dt, _CANDIDATES[-1] * 2.0, polyorder=3)[0]
    if scores.max() <= _MIN_EXPLAINED * np.mean(np.sum(fast**2, axis=1)):
        raise ValueError("demo: no rhythm found (no period between "
                         f"{_CANDIDATES[0]:g} s and {_CANDIDATES[-1]:g} s explains the motion beyond its slow part)")
    inner = np.arange(1, scores.size - 1)
    peaks = inner[(scores[inner] >= scores[inner - 1]) & (scores[inner] > scores[inner + 1])]
    peaks = np.append(peaks[scores[peaks] >= 0.5 * scores.max()], np.argmax(scores))
    return float(_CANDIDATES[peaks[0]])


def _longest_run(mask: np.ndarray) -> tuple[int, int]:
    """``(first, stop)`` of the longest run of True in ``mask [L]`` (``(0, 0)`` if none)."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(np.int8), [0]])))
    starts, stops = edges[::2], edges[1::2]
    if starts.size == 0:
        return 0, 0
    best = int(np.argmax(stops - starts))
    return int(starts[best]), int(stops[best])


def _local_fit(demo: Demonstration, period: float, step: float) -> tuple[np.ndarray, np.ndarray, float]:
    """Local fits every ``step`` s from ``demo.t[0]``: slow part ``[C, d]``, rhythm amplitude ``[C]`` at the centres,
    and the mean square per sample (m^2) that the harmonics explain beyond the polynomials (over all windows)."""
    t = demo.t - demo.t[0]
    half = period
    centres = np.arange(0.0, t[-1] + step, step)
    order = np.arange(1, _N_HARMONICS + 1)
    slow = np.empty((centres.size, demo.n_dims))
    amplitude = np.empty(centres.size)
    counted, explained = 0, 0.0
    for i, centre in enumerate(centres):
        low, high = np.searchsorted(t, [centre - half, centre + half])
        tau = t[low:high] - centre
        angle = (2.0 * np.pi / period) * tau[:, None] * order
        design = np.hstack([(tau[:, None] / half) ** np.arange(_DEGREE + 1), np.cos(angle), np.sin(angle)])
        samples = demo.Y[low:high]
        coefficients, full_residual, *_ = np.linalg.lstsq(design, samples, rcond=None)
        polynomial = np.linalg.lstsq(design[:, :_DEGREE + 1], samples, rcond=None)[1]
        if full_residual.size and polynomial.size:
            counted += high - low
            explained += float(polynomial.sum() - full_residual.sum())
        slow[i] = coefficients[0]
        amplitude[i] = np.sqrt(np.sum(coefficients[_DEGREE + 1:] ** 2))
    return slow, amplitude, explained / max(counted, 1)


def local_fit(demo: Demonstration, period: float) -> tuple[np.ndarray, np.ndarray]:
    """Slow part ``[L, d]`` and rhythm amplitude ``[L]`` (m) of ``demo``: a cubic polynomial plus ``_N_HARMONICS``
    harmonics of ``period`` fitted by least squares in two-period windows centred every ``_STEP`` s, interpolated
    to the samples."""
    slow, amplitude, _ = _local_fit(demo, period, _STEP)
    t = demo.t - demo.t[0]
    centres = np.arange(slow.shape[0]) * _STEP
    return (np.stack([np.interp(t, centres, column) for column in slow.T], axis=1),
            np.interp(t, centres, amplitude))


def segment_rhythm(demo: Demonstration, *, period: float | None = None, start: float | None = None,
                   end: float | None = None, begin: float = 0.15, full: float = 0.75,
                   rest_fraction: float = 0.05, min_periods: float = 2.0) -> RhythmSegmentation:
    """Find the rhythm in a whole recording and the rests around it (see the module docstring).

    Args:
        demo: the recording on an even grid (outliers removed, e.g. :func:`rdmp_gym.recordings.to_demonstration`).
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
    estimate = _coarse_period(demo) if period is None else check_positive(period, "period")
    slow, amplitude = local_fit(demo, estimate)
    first, last = _rhythm_bounds(t, amplitude, full, start, end)
    if period is None:      # refine on the full-size rhythm, then fit again with the refined period
        Z = demo.Y[first:last + 1] - slow[first:last + 1]
        estimate = _refine_period(t[first:last + 1], Z / np.maximum(np.std(Z, axis=0), 1e-12), estimate, demo.dt,
                                  12, 0.1)
        slow, amplitude = local_fit(demo, estimate)
        first, last = _rhythm_bounds(t, amplitude, full, start, end)
    if (t[last] - t[first]) / estimate < min_periods:
        raise ValueError(f"demo: the rhythm spans only {(t[last] - t[first]) / estimate:.1f} periods "
                         f"({t[first]:.3g} s to {t[last]:.3g} s), need at least {min_periods:g}")
    speed = motion_speed(demo)
    if start is None:
        first = _arrival(slow, speed, first, last, demo.dt)
    level = _high_level(amplitude[first:last + 1])
    growing = np.flatnonzero(amplitude[:first + 1] < begin * level)
    entry = int(growing[-1]) if growing.size else first
    if end is None:
        last = _departure(slow, speed, first, last, demo.dt)
    threshold = max(rest_fraction * float(np.median(speed[first:last + 1])),
                    _NOISE_FACTOR * _noise_speed(speed, demo.dt))
    moving = np.flatnonzero(speed[:entry + 1] >= threshold)
    onset = int(moving[0]) if moving.size else entry
    rest = rest_onset(speed, threshold, demo.dt)
    rest_time = None if rest is None or rest <= last else float(t[rest])
    logger.debug("segment_rhythm %r: period %.4f s, onset %.2f, entry %.2f, rhythm %.2f-%.2f s, rest %s",
                 demo.name, estimate, t[onset], t[entry], t[first], t[last], rest_time)
    return RhythmSegmentation(period=float(estimate), onset=float(t[onset]), entry=float(t[entry]),
                              rhythm_start=float(t[first]), rhythm_end=float(t[last]), rest_time=rest_time,
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
    level = _high_level(amplitude)
    low, high = _longest_run(amplitude >= full * level)
    if high == 0:
        raise ValueError("demo: no rhythm found (its amplitude never reaches its typical level)")
    first = low if start is None else int(np.searchsorted(t, start))
    last = high - 1 if end is None else int(min(np.searchsorted(t, end), t.size - 1))
    return first, last
