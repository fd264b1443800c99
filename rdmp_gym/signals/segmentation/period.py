"""The period of a rhythm: one estimator (:func:`estimate_period`) with two methods, and its refinement.

``estimate_period(demo, method=...)`` gives a coarse period; the segmentations refine it with
:func:`refine_period` on the part they find periodic.

* ``"autocorrelation"`` (used by :func:`~rdmp_gym.signals.segmentation.segment` on demonstrations): the first strong
  peak of the autocorrelation of the detrended last half of the demonstration, each dimension centred and divided by its
  range. Needs that last half to be periodic.
* ``"local_fit"`` (used by :func:`~rdmp_gym.signals.segmentation.segment_rhythm` on whole recordings): of candidate
  periods from 0.3 s to 4 s, the shortest that explains most of the motion beyond local polynomials
  (:func:`~rdmp_gym.signals.segmentation.fourier.windowed_fit`). Finds a rhythm that runs for only part of a recording,
  under a large slow motion.

The two methods give different coarse numbers on the same signal (they measure different things); each
segmentation keeps the method it was published with.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import minimize_scalar
from scipy.signal import detrend

from rdmp_gym.signals.demonstrations import Demonstration
from rdmp_gym.signals.filters import smooth_derivatives

from .fourier import fourier_fit, normalised, usable_harmonics, windowed_fit

__all__ = ["PERIOD_METHODS", "estimate_period", "refine_period"]

PERIOD_METHODS = ("autocorrelation", "local_fit")
"""The methods of :func:`estimate_period`."""

_MIN_CORRELATION = 0.5  # weakest autocorrelation peak accepted as periodicity
_CANDIDATES = np.geomspace(0.3, 4.0, 45)   # s: the periods the local-fit search tries
_MIN_EXPLAINED = 0.2        # least share of the motion beyond a slow trend that the rhythm must explain
_GRID_SIZE = 21  # nodes of the refinement's grid search


def estimate_period(demo: Demonstration, method: str = "autocorrelation") -> float:
    """Coarse period (s) of the rhythm in ``demo`` by ``method`` (one of :data:`PERIOD_METHODS`, see the module).

    Raises ValueError if no periodicity is found."""
    if method == "autocorrelation":
        return _autocorrelation_period(normalised(demo.Y)[0], demo.dt)
    if method == "local_fit":
        return _local_fit_period(demo)
    raise ValueError(f"method: expected one of {PERIOD_METHODS}, got {method!r}")


def _autocorrelation_period(Z: np.ndarray, dt: float) -> float:
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


def _local_fit_period(demo: Demonstration) -> float:
    """Coarse period (s) of the rhythm in ``demo``: of the candidate periods (``_CANDIDATES``), the shortest local
    maximum of what the harmonics explain beyond the local polynomials (:func:`windowed_fit`) that reaches half the
    most any candidate explains (a fraction of the period explains little; a multiple explains as much, and more
    of the slow motion that its longer windows leave to the harmonics)."""
    scores = np.array([windowed_fit(demo, candidate, candidate)[2] for candidate in _CANDIDATES])
    fast = demo.Y - smooth_derivatives(demo.Y, demo.dt, _CANDIDATES[-1] * 2.0, polyorder=3)[0]
    if scores.max() <= _MIN_EXPLAINED * np.mean(np.sum(fast**2, axis=1)):
        raise ValueError("demo: no rhythm found (no period between "
                         f"{_CANDIDATES[0]:g} s and {_CANDIDATES[-1]:g} s explains the motion beyond its slow part)")
    inner = np.arange(1, scores.size - 1)
    peaks = inner[(scores[inner] >= scores[inner - 1]) & (scores[inner] > scores[inner + 1])]
    peaks = np.append(peaks[scores[peaks] >= 0.5 * scores.max()], np.argmax(scores))
    return float(_CANDIDATES[peaks[0]])


def refine_period(t: np.ndarray, Z: np.ndarray, period: float, dt: float, n_harmonics: int,
                  span: float) -> float:
    """The period within ``period * (1 +- span)`` that minimises the Fourier-fit residual of
    ``Z[n, d]`` on ``t[n]`` (a grid search, then a bounded scalar search around the best node)."""
    k = usable_harmonics(t.size, period, dt, n_harmonics)
    t = t - t.mean()

    def cost(candidate: float) -> float:
        return fourier_fit(t, Z, candidate, k)[1]

    grid = period * (1.0 + np.linspace(-span, span, _GRID_SIZE))
    best = int(np.argmin([cost(candidate) for candidate in grid]))
    low, high = grid[max(best - 1, 0)], grid[min(best + 1, grid.size - 1)]
    result = minimize_scalar(cost, bounds=(low, high), method="bounded",
                             options={"xatol": 1e-9 * period})
    return float(result.x)
