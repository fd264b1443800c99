"""Filters of sampled signals ``Y [L, d]`` on an even grid: smoothed derivatives (Savitzky-Golay).

The fit (:mod:`rdmp_gym.fitting`), the segmentation of whole recordings (:mod:`rdmp_gym.segmentation`) and the
stop's fit read velocities and accelerations of noisy samples through :func:`smooth_derivatives`.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import savgol_filter

from .validation import check_positive

__all__ = ["smooth_derivatives"]


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
