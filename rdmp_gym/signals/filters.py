"""Filters of sampled signals ``Y [L, d]``: outliers (:func:`despike`) and smoothed derivatives (Savitzky-Golay).

The fit (:mod:`rdmp_gym.dmp.fitting`), the segmentation of whole recordings (:mod:`rdmp_gym.signals.segmentation`) and
the stop's fit read velocities and accelerations of noisy samples through :func:`smooth_derivatives`; a recorder's
samples lose their outliers through :func:`despike` (:func:`rdmp_gym.signals.demonstrations.to_demonstration`).
:func:`runs` and :func:`longest_run` find the stretches where a condition on the samples holds.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import median_filter
from scipy.signal import savgol_filter

from ..validation import as_finite_array, check_positive

__all__ = ["despike", "longest_run", "runs", "smooth_derivatives"]


def smooth_derivatives(Y: np.ndarray, dt: float, window: float, polyorder: int = 5
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Savitzky-Golay estimates of position, velocity and acceleration of ``Y [L, d]`` sampled every ``dt``.

    ``window`` is the filter length in seconds (rounded to an odd number of samples, at least
    ``polyorder + 2``). Returns three ``[L, d]`` arrays.
    """
    window = check_positive(window, "smoothing")
    length = max(round(window / dt) | 1, polyorder + 2 + (polyorder % 2))
    length = min(length, Y.shape[0] - (1 - Y.shape[0] % 2))
    if length <= polyorder:
        raise ValueError(f"demos: too few samples ({Y.shape[0]}) to estimate derivatives")
    kwargs = dict(window_length=length, polyorder=polyorder, axis=0, delta=dt, mode="interp")
    return (savgol_filter(Y, deriv=0, **kwargs), savgol_filter(Y, deriv=1, **kwargs),
            savgol_filter(Y, deriv=2, **kwargs))


def despike(Y: np.ndarray, window: int = 7, threshold: float = 6.0) -> np.ndarray:
    """``Y [L, d]`` with outliers replaced by the running median (a Hampel filter).

    A sample is an outlier where it differs from the median of the ``window`` samples around it by more than
    ``threshold`` times the median absolute difference over the whole signal (1.4826 MAD: the noise's standard
    deviation for Gaussian noise; at least 1e-3 of the signal's range), in any dimension.
    """
    Y = as_finite_array(Y, "Y", ndim=2)
    if window < 3 or window % 2 == 0:
        raise ValueError(f"window: expected an odd number >= 3, got {window!r}")
    median = median_filter(Y, size=(window, 1), mode="nearest")
    deviation = np.abs(Y - median)
    scale = 1.4826 * np.median(deviation, axis=0)
    floor = 1e-3 * np.maximum(np.ptp(Y, axis=0), 1e-12)   # a noise-free signal: only jumps of its size
    outlier = deviation > threshold * np.maximum(scale, floor)
    return np.where(outlier, median, Y)


def runs(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(starts, stops)``: the runs of True in ``mask [L]``, ``mask[starts[k]:stops[k]]`` each (``[R]`` ints)."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], np.asarray(mask).astype(np.int8), [0]])))
    return edges[::2], edges[1::2]


def longest_run(mask: np.ndarray) -> tuple[int, int]:
    """``(first, stop)`` of the longest run of True in ``mask [L]`` (the earliest of equals; ``(0, 0)`` if none)."""
    starts, stops = runs(mask)
    if starts.size == 0:
        return 0, 0
    best = int(np.argmax(stops - starts))
    return int(starts[best]), int(stops[best])
