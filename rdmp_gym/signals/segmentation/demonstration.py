"""Segmentation of a composed-periodic demonstration (Ernesti et al. 2012, IV and V-A): period,
transient length, anchor, and the phase shift between the periodic parts of two demonstrations.

Method. Each dimension is centred and divided by its range, so dimensions of any unit and size
combine. A coarse period comes from the autocorrelation of the detrended last half of the signal
(:func:`~rdmp_gym.signals.segmentation.period.estimate_period`, method ``"autocorrelation"``). It is refined by fitting
a truncated Fourier series (``n_harmonics`` harmonics) to the periodic part and minimising the residual over
the period (:func:`~rdmp_gym.signals.segmentation.period.refine_period`). The fitted series, extended over the whole
demonstration, is the periodic template; the residual against it, weighted by the noise level
measured on the periodic part, is large in the transient and pure noise after it. The transient
length is the change point that best separates the two (a one-sided CUSUM; the template, its residual and the
change point are in :mod:`rdmp_gym.signals.segmentation.fourier`). Period, template and
change point are re-estimated on the periodic part found, until the change point settles.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize_scalar

from rdmp_gym.signals.demonstrations import Demonstration
from rdmp_gym.validation import as_finite_array, check_positive

from .fourier import change_point, fourier_fit, normalised, scaled_residual, usable_harmonics
from .period import estimate_period, refine_period

__all__ = ["Segmentation", "phase_shift", "segment"]

logger = logging.getLogger(__name__)

_SEARCH_SPAN = 0.03  # relative half-width of the first period search around the coarse estimate
_PHASE_GRID = 360  # nodes of the phase-shift search over one period
_MAX_ITERATIONS = 5  # re-estimations of period, template and change point
_MIN_EXPLAINED = 0.8  # least share of the periodic part's variance the periodic template must explain


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
    Z, mean, scale = normalised(demo.Y)
    estimate = estimate_period(demo, "autocorrelation") if period is None else period
    start, span = Z.shape[0] // 2, _SEARCH_SPAN
    for _ in range(_MAX_ITERATIONS):
        if t[-1] - t[start] < estimate:
            break
        if period is None:
            estimate = refine_period(t[start:], Z[start:], estimate, dt, n_harmonics, span)
            span = 0.1 * _SEARCH_SPAN
        previous = start
        start = change_point(scaled_residual(t, Z, slice(start, None), estimate, dt, n_harmonics), margin)
        if start == previous:
            break
    transient_length = float(t[start])
    n_periods = (t[-1] - transient_length) / estimate
    if n_periods < min_periods:
        raise ValueError(f"demo: only {n_periods:.1f} periods after the transient, "
                         f"need at least {min_periods:g}")
    k = usable_harmonics(t.size - start, estimate, dt, n_harmonics)
    coefficients, rss = fourier_fit(t[start:], Z[start:], estimate, k)
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
    k = usable_harmonics(int(periodic.sum()), period, demo.dt, n_harmonics)
    if tau[periodic][-1] < period:
        raise ValueError(f"{name}: the periodic part is shorter than one period ({period:.4g} s)")
    coefficients, _ = fourier_fit(tau[periodic], demo.Y[periodic], period, k)
    return coefficients[1:k + 1] - 1j * coefficients[k + 1:]


def _check_segmented(demo: object, seg: object, name: str) -> None:
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
    _check_segmented(reference, reference_seg, "reference")
    _check_segmented(other, other_seg, "other")
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
