"""Segmentation of a composed-periodic demonstration (Ernesti et al. 2012, IV and V-A): period,
transient length, anchor, and the phase shift between the periodic parts of two demonstrations.

Method. Each dimension is centred and divided by its range, so dimensions of any unit and size
combine. A coarse period comes from the autocorrelation of the detrended last half of the signal.
It is refined by fitting a truncated Fourier series (``n_harmonics`` harmonics) to the periodic
part and minimising the residual over the period. The fitted series, extended over the whole
demonstration, is the periodic template; the residual against it, weighted by the noise level
measured on the periodic part, is large in the transient and pure noise after it. The transient
length is the change point that best separates the two (a one-sided CUSUM). Period, template and
change point are re-estimated on the periodic part found, until the change point settles.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize_scalar
from scipy.signal import detrend

from rdmp_gym.demonstrations import Demonstration
from rdmp_gym.validation import as_finite_array, check_positive

__all__ = ["Segmentation", "phase_shift", "segment"]

logger = logging.getLogger(__name__)

_MIN_CORRELATION = 0.5  # weakest autocorrelation peak accepted as periodicity
_SEARCH_SPAN = 0.03  # relative half-width of the first period search around the coarse estimate
_GRID_SIZE = 21  # nodes of that search
_PHASE_GRID = 360  # nodes of the phase-shift search over one period
_MAX_ITERATIONS = 5  # re-estimations of period, template and change point
_MIN_EXPLAINED = 0.8  # least share of the periodic part's variance the periodic template must explain
_NOISE_FLOOR = 1e-6  # smallest noise level assumed, relative to the range of a dimension


@dataclass(frozen=True, eq=False)
class Segmentation:
    """Result of :func:`segment`.

    Attributes:
        period: period of the periodic part (s).
        transient_length: time from ``demo.t[0]`` to the start of the periodic part (s).
        anchor: ``[d]`` mean of the periodic part over a whole number of periods.
    """

    period: float
    transient_length: float
    anchor: np.ndarray

    def __post_init__(self) -> None:
        object.__setattr__(self, "period", check_positive(self.period, "period"))
        transient = float(as_finite_array(self.transient_length, "transient_length", ndim=0))
        if transient < 0.0:
            raise ValueError(f"transient_length: expected >= 0, got {transient!r}")
        object.__setattr__(self, "transient_length", transient)
        anchor = as_finite_array(self.anchor, "anchor", ndim=1)
        anchor.setflags(write=False)
        object.__setattr__(self, "anchor", anchor)


def _check_harmonics(n_harmonics: int) -> None:
    if isinstance(n_harmonics, bool) or not isinstance(n_harmonics, (int, np.integer)) \
            or n_harmonics < 1:
        raise ValueError(f"n_harmonics: expected a positive int, got {n_harmonics!r}")


def _normalised(Y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(Y - mean) / scale`` ``[L, d]``, ``mean`` ``[d]`` and ``scale`` ``[d]`` (each dimension's
    range; 1 for a constant dimension)."""
    span = np.ptp(Y, axis=0)
    mean, scale = Y.mean(axis=0), np.where(span > 0.0, span, 1.0)
    return (Y - mean) / scale, mean, scale


def _coarse_period(Z: np.ndarray, dt: float) -> float:
    """Period (s) from the autocorrelation of the detrended last half of ``Z[L, d]``."""
    tail = detrend(Z[Z.shape[0] // 2:], axis=0)
    n = tail.shape[0]
    size = 1 << int(np.ceil(np.log2(2 * n)))
    spectrum = np.fft.rfft(tail, size, axis=0)
    raw = np.fft.irfft(np.abs(spectrum) ** 2, size, axis=0)[:n].sum(axis=1)
    if raw[0] <= 0.0:
        raise ValueError("demo: no periodicity found (the signal is constant)")
    acf = raw / (n - np.arange(n)) / (raw[0] / n)  # unbiased, 1 at lag 0
    max_lag = (2 * n) // 3
    negative = np.flatnonzero(acf[:max_lag] < 0.0)
    if negative.size == 0:
        raise ValueError("demo: no periodicity found (the autocorrelation never turns negative)")
    lags = np.arange(negative[0] + 1, max_lag - 1)
    peaks = lags[(acf[lags] >= acf[lags - 1]) & (acf[lags] > acf[lags + 1])]
    if peaks.size == 0:
        raise ValueError(f"demo: no periodicity found: the last half of the demonstration ({n * dt:.3g} s) "
                         "does not repeat a pattern; record at least two more periods after the transient")
    if acf[peaks].max() < _MIN_CORRELATION:
        best = acf[peaks].max()
        raise ValueError(f"demo: no periodicity found (best autocorrelation peak {best:.2f}, "
                         f"need {_MIN_CORRELATION})")
    lag = peaks[np.argmax(acf[peaks] >= 0.9 * acf[peaks].max())]
    left, mid, right = acf[lag - 1], acf[lag], acf[lag + 1]
    curvature = left - 2.0 * mid + right
    offset = 0.5 * (left - right) / curvature if curvature < 0.0 else 0.0
    return float((lag + offset) * dt)


def _design(t: np.ndarray, period: float, n_harmonics: int) -> np.ndarray:
    """Fourier design matrix ``[n, 2K + 1]``: 1, cos(k w t), sin(k w t) for k = 1..K."""
    angle = (2.0 * np.pi / period) * t[:, None] * np.arange(1, n_harmonics + 1)
    return np.hstack([np.ones((t.size, 1)), np.cos(angle), np.sin(angle)])


def _harmonics(n_samples: int, period: float, dt: float, n_harmonics: int) -> int:
    """Number of harmonics usable for ``n_samples`` samples: below 0.4 x the sampling rate."""
    return max(1, min(n_harmonics, int(0.4 * period / dt), (n_samples - 1) // 4))


def _fit(t: np.ndarray, Z: np.ndarray, period: float, n_harmonics: int) -> tuple[np.ndarray, float]:
    """Least-squares Fourier coefficients ``[2K + 1, d]`` of ``Z[n, d]`` and the residual sum."""
    design = _design(t, period, n_harmonics)
    coefficients, *_ = np.linalg.lstsq(design, Z, rcond=None)
    residual = Z - design @ coefficients
    return coefficients, float(np.sum(residual**2))


def _refine_period(t: np.ndarray, Z: np.ndarray, period: float, dt: float, n_harmonics: int,
                   span: float) -> float:
    """The period within ``period * (1 +- span)`` that minimises the Fourier-fit residual of
    ``Z[n, d]`` on ``t[n]`` (a grid search, then a bounded scalar search around the best node)."""
    k = _harmonics(t.size, period, dt, n_harmonics)
    t = t - t.mean()

    def cost(candidate: float) -> float:
        return _fit(t, Z, candidate, k)[1]

    grid = period * (1.0 + np.linspace(-span, span, _GRID_SIZE))
    best = int(np.argmin([cost(candidate) for candidate in grid]))
    low, high = grid[max(best - 1, 0)], grid[min(best + 1, grid.size - 1)]
    result = minimize_scalar(cost, bounds=(low, high), method="bounded",
                             options={"xatol": 1e-9 * period})
    return float(result.x)


def _scaled_residual(t: np.ndarray, Z: np.ndarray, start: int, period: float, dt: float,
                     n_harmonics: int) -> np.ndarray:
    """Residual ``[L, d]`` of ``Z[L, d]`` against the Fourier template fitted on samples
    ``start:``, each dimension divided by its noise level measured there."""
    k = _harmonics(t.size - start, period, dt, n_harmonics)
    coefficients, _ = _fit(t[start:], Z[start:], period, k)
    residual = Z - _design(t, period, k) @ coefficients
    dof = max(t.size - start - coefficients.shape[0], 1)
    noise = np.sqrt(np.sum(residual[start:] ** 2, axis=0) / dof)
    return residual / np.maximum(noise, _NOISE_FLOOR)


def _change_point(residual: np.ndarray, margin: float) -> int:
    """Index of the first periodic sample, from noise-scaled residuals ``residual[L, d]``.

    Minimises the sum over samples j >= k of ``|r_j|^2 - (d + margin)``: samples that fit the
    template better than noise plus margin count as periodic, the rest as transient.
    """
    excess = np.sum(residual**2, axis=1) - (residual.shape[1] + margin)
    tail_sums = np.cumsum(excess[::-1])[::-1]
    return int(np.argmin(tail_sums))


def segment(demo: Demonstration, *, period: float | None = None, min_periods: float = 2.0,
            n_harmonics: int = 12, margin: float = 2.0) -> Segmentation:
    """Period, transient length and anchor of a composed-periodic demonstration.

    Args:
        demo: the demonstration, ``Y[L, d]`` on an even grid; its last half must be periodic
            and span at least 1.5 periods.
        period: the known period (s), used as is; ``None`` estimates it.
        min_periods: the fewest periods (>= 1) the periodic part must span.
        n_harmonics: the most harmonics of the Fourier template of the periodic part.
        margin: how much worse than noise (per sample, in units of the noise variance) a sample
            may fit the periodic template and still count as periodic.

    The transient length is where the demonstration becomes periodic within its noise: with
    noise, the end of a smooth approach that deviates from the pattern by less than about
    ``sqrt(margin)`` noise deviations counts as periodic.

    Raises ValueError if ``demo`` shows no periodicity or fewer than ``min_periods`` periods after
    the transient, or if an argument is out of range.
    """
    if not isinstance(demo, Demonstration):
        raise TypeError(f"demo: expected a Demonstration, got {type(demo).__name__}")
    if period is not None:
        period = check_positive(period, "period")
    min_periods = check_positive(min_periods, "min_periods")
    if min_periods < 1.0:
        raise ValueError(f"min_periods: expected at least 1, got {min_periods!r}")
    margin = check_positive(margin, "margin")
    _check_harmonics(n_harmonics)
    t, dt = demo.t - demo.t[0], demo.dt
    Z, mean, scale = _normalised(demo.Y)
    estimate = _coarse_period(Z, dt) if period is None else period
    start, span = Z.shape[0] // 2, _SEARCH_SPAN
    for _ in range(_MAX_ITERATIONS):
        if t[-1] - t[start] < estimate:
            break
        if period is None:
            estimate = _refine_period(t[start:], Z[start:], estimate, dt, n_harmonics, span)
            span = 0.1 * _SEARCH_SPAN
        previous = start
        start = _change_point(_scaled_residual(t, Z, start, estimate, dt, n_harmonics), margin)
        if start == previous:
            break
    transient_length = float(t[start])
    n_periods = (t[-1] - transient_length) / estimate
    if n_periods < min_periods:
        raise ValueError(f"demo: only {n_periods:.1f} periods after the transient, "
                         f"need at least {min_periods:g}")
    k = _harmonics(t.size - start, estimate, dt, n_harmonics)
    coefficients, rss = _fit(t[start:], Z[start:], estimate, k)
    total = float(np.sum((Z[start:] - Z[start:].mean(axis=0)) ** 2))
    explained = 1.0 - rss / total if total > 0.0 else 0.0
    if explained < _MIN_EXPLAINED:
        raise ValueError(f"demo: no periodicity found (a pattern of period {estimate:.4g} s "
                         f"explains {explained:.0%} of the variance after the transient, "
                         f"need {_MIN_EXPLAINED:.0%})")
    logger.debug("segment %r: period %.6f s, transient %.3f s, %.1f periods, %.4f explained",
                 demo.name, estimate, transient_length, n_periods, explained)
    return Segmentation(period=estimate, transient_length=transient_length,
                        anchor=mean + scale * coefficients[0])


def _periodic_coefficients(demo: Demonstration, seg: Segmentation, period: float,
                           n_harmonics: int, name: str) -> np.ndarray:
    """Complex Fourier coefficients ``c[K, d]`` (harmonics 1..K) of the periodic part of ``demo``,
    time measured from its transient length T: ``y(T + tau) = a0 + Re sum_k c_k exp(i k w tau)``."""
    tau = demo.t - demo.t[0] - seg.transient_length
    periodic = tau >= -0.5 * demo.dt
    k = _harmonics(int(periodic.sum()), period, demo.dt, n_harmonics)
    if tau[periodic][-1] < period:
        raise ValueError(f"{name}: the periodic part is shorter than one period ({period:.4g} s)")
    coefficients, _ = _fit(tau[periodic], demo.Y[periodic], period, k)
    return coefficients[1:k + 1] - 1j * coefficients[k + 1:]


def _check_pair(demo: object, seg: object, name: str) -> None:
    if not isinstance(demo, Demonstration):
        raise TypeError(f"{name}: expected a Demonstration, got {type(demo).__name__}")
    if not isinstance(seg, Segmentation):
        raise TypeError(f"{name}_seg: expected a Segmentation, got {type(seg).__name__}")
    if seg.transient_length >= demo.duration:
        raise ValueError(f"{name}_seg: transient_length {seg.transient_length} s is not shorter "
                         f"than the demonstration ({demo.duration} s)")


def phase_shift(reference: Demonstration, reference_seg: Segmentation, other: Demonstration,
                other_seg: Segmentation, period: float | None = None, *,
                n_harmonics: int = 12) -> float:
    """The shift ``s`` in ``[0, period)`` (s) that aligns two periodic parts.

    ``other(T_o + tau) ~ reference(T_r + s + tau)`` for ``tau >= 0``, where ``T_r``, ``T_o`` are the
    segmentations' transient lengths (the paper's phase shift, V-A). Both periodic parts are fitted
    with a Fourier series of period ``period`` (default ``reference_seg.period``); ``s`` minimises
    the distance between the series' harmonics (the mean is left out, so anchors may differ), each
    dimension weighted by the inverse square of the reference's range.
    """
    _check_pair(reference, reference_seg, "reference")
    _check_pair(other, other_seg, "other")
    if other.n_dims != reference.n_dims:
        raise ValueError(f"other: has {other.n_dims} dimension(s), "
                         f"reference has {reference.n_dims}")
    period = check_positive(reference_seg.period if period is None else period, "period")
    _check_harmonics(n_harmonics)
    c_ref = _periodic_coefficients(reference, reference_seg, period, n_harmonics, "reference")
    c_other = _periodic_coefficients(other, other_seg, period, n_harmonics, "other")
    k = min(c_ref.shape[0], c_other.shape[0])
    span = np.ptp(reference.Y, axis=0)
    weights = 1.0 / np.where(span > 0.0, span, 1.0) ** 2
    c_ref, c_other = c_ref[:k] * np.sqrt(weights), c_other[:k] * np.sqrt(weights)
    orders = np.arange(1, k + 1)[:, None]

    def cost(shift: float) -> float:
        rotated = c_ref * np.exp(1j * orders * (2.0 * np.pi / period) * shift)
        return float(np.sum(np.abs(c_other - rotated) ** 2))

    grid = np.linspace(0.0, period, _PHASE_GRID, endpoint=False)
    best = grid[int(np.argmin([cost(shift) for shift in grid]))]
    step = period / _PHASE_GRID
    result = minimize_scalar(cost, bounds=(best - step, best + step), method="bounded",
                             options={"xatol": 1e-9 * period})
    shift = float(np.mod(result.x, period))
    return 0.0 if shift >= period else shift
