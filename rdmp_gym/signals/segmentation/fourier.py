"""Least-squares Fourier fits, the shared arithmetic of every segmentation.

* The periodic template: a truncated Fourier series of a known period fitted to a periodic part
  (:func:`fourier_design`, :func:`fourier_fit`, :func:`usable_harmonics`), its residual over the whole signal
  scaled by the noise level measured where it was fitted (:func:`scaled_residual`), and the change point that
  separates samples that fit it from those that do not (:func:`change_point`). Signals enter centred and divided
  by their range (:func:`normalised`), so dimensions of any unit and size combine.
* Local fits: a cubic polynomial plus a few harmonics of a period, fitted in windows of two periods that slide
  along a recording (:func:`windowed_fit`, :func:`local_fit`). The polynomial is the slow part of the motion,
  the harmonics' size the rhythm's local amplitude.
"""

from __future__ import annotations

import numpy as np

from rdmp_gym.signals.demonstrations import Demonstration

__all__ = ["LOCAL_STEP", "NOISE_FLOOR", "change_point", "fourier_design", "fourier_fit", "local_fit", "normalised",
           "scaled_residual", "usable_harmonics", "windowed_fit"]

NOISE_FLOOR = 1e-6
"""Smallest noise level assumed by :func:`scaled_residual`, relative to the range of a dimension."""

LOCAL_STEP = 0.05
"""Spacing (s) of the local fits of :func:`local_fit` (interpolated between)."""

_LOCAL_HARMONICS = 4        # harmonics of the local Fourier fit
_DEGREE = 3                 # degree of the local polynomial


# ---------------------------------------------------------------------------------- the periodic template
def normalised(Y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(Y - mean) / scale`` ``[L, d]``, ``mean`` ``[d]`` and ``scale`` ``[d]`` (each dimension's
    range; 1 for a constant dimension)."""
    span = np.ptp(Y, axis=0)
    mean, scale = Y.mean(axis=0), np.where(span > 0.0, span, 1.0)
    return (Y - mean) / scale, mean, scale


def fourier_design(t: np.ndarray, period: float, n_harmonics: int) -> np.ndarray:
    """Fourier design matrix ``[n, 2K + 1]``: 1, cos(k w t), sin(k w t) for k = 1..K."""
    angle = (2.0 * np.pi / period) * t[:, None] * np.arange(1, n_harmonics + 1)
    return np.hstack([np.ones((t.size, 1)), np.cos(angle), np.sin(angle)])


def usable_harmonics(n_samples: int, period: float, dt: float, n_harmonics: int) -> int:
    """Number of harmonics usable for ``n_samples`` samples: below 0.4 x the sampling rate."""
    return max(1, min(n_harmonics, int(0.4 * period / dt), (n_samples - 1) // 4))


def fourier_fit(t: np.ndarray, Z: np.ndarray, period: float, n_harmonics: int) -> tuple[np.ndarray, float]:
    """Least-squares Fourier coefficients ``[2K + 1, d]`` of ``Z[n, d]`` and the residual sum."""
    design = fourier_design(t, period, n_harmonics)
    coefficients, *_ = np.linalg.lstsq(design, Z, rcond=None)
    residual = Z - design @ coefficients
    return coefficients, float(np.sum(residual**2))


def scaled_residual(t: np.ndarray, Z: np.ndarray, fitted: slice, period: float, dt: float,
                    n_harmonics: int) -> np.ndarray:
    """Residual ``[L, d]`` of ``Z[L, d]`` on ``t[L]`` against the Fourier template fitted on the samples
    ``fitted``, each dimension divided by its noise level measured there (at least :data:`NOISE_FLOOR`)."""
    n_fitted = len(range(*fitted.indices(t.size)))
    k = usable_harmonics(n_fitted, period, dt, n_harmonics)
    coefficients, _ = fourier_fit(t[fitted], Z[fitted], period, k)
    residual = Z - fourier_design(t, period, k) @ coefficients
    dof = max(n_fitted - coefficients.shape[0], 1)
    noise = np.sqrt(np.sum(residual[fitted] ** 2, axis=0) / dof)
    return residual / np.maximum(noise, NOISE_FLOOR)


def change_point(residual: np.ndarray, margin: float) -> int:
    """Index of the first periodic sample, from noise-scaled residuals ``residual[L, d]``
    (:func:`scaled_residual`).

    Minimises the sum over samples j >= k of ``|r_j|^2 - (d + margin)``: samples that fit the
    template better than noise plus margin count as periodic, the rest as transient (a one-sided CUSUM).
    Read backwards (``residual[::-1]``) it finds where a periodic part ends.
    """
    excess = np.sum(residual**2, axis=1) - (residual.shape[1] + margin)
    tail_sums = np.cumsum(excess[::-1])[::-1]
    return int(np.argmin(tail_sums))


# ---------------------------------------------------------------------------------- local fits
def windowed_fit(demo: Demonstration, period: float, step: float) -> tuple[np.ndarray, np.ndarray, float]:
    """Local fits every ``step`` s from ``demo.t[0]``: slow part ``[C, d]``, rhythm amplitude ``[C]`` at the centres,
    and the mean square per sample (m^2) that the harmonics explain beyond the polynomials (over all windows)."""
    t = demo.t - demo.t[0]
    half = period
    centres = np.arange(0.0, t[-1] + step, step)
    order = np.arange(1, _LOCAL_HARMONICS + 1)
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
    """Slow part ``[L, d]`` and rhythm amplitude ``[L]`` (m) of ``demo``: a cubic polynomial plus four harmonics of
    ``period`` fitted by least squares in two-period windows centred every :data:`LOCAL_STEP` s
    (:func:`windowed_fit`), interpolated to the samples."""
    slow, amplitude, _ = windowed_fit(demo, period, LOCAL_STEP)
    t = demo.t - demo.t[0]
    centres = np.arange(slow.shape[0]) * LOCAL_STEP
    return (np.stack([np.interp(t, centres, column) for column in slow.T], axis=1),
            np.interp(t, centres, amplitude))
