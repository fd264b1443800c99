"""Imitation: the target forcing term (10) from a demonstration and the two regressions.

* ``lwr``: locally weighted regression exactly as the paper's (11)/(12): each weight is the
  activation-weighted mean of the target, one basis function at a time.
* ``ridge``: beyond the paper, one regularised least-squares problem on the normalised basis, so the
  mixture (5) itself (not each basis function separately) fits the target; all weights at once.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import savgol_filter

from .basis import normalize
from .validation import check_positive

__all__ = ["FIT_METHODS", "fit_weights", "forcing_target", "smooth_derivatives"]

FIT_METHODS = ("lwr", "ridge")


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


def forcing_target(Y: np.ndarray, Yd: np.ndarray, Ydd: np.ndarray, anchor: np.ndarray, omega: float,
                   alpha_z: float) -> np.ndarray:
    """Eq. (10): ``f = ydd / Omega^2 - alpha_z (beta_z (g - y) - yd / Omega)``, all ``[L, d]``."""
    beta_z = alpha_z / 4.0
    return Ydd / omega**2 - alpha_z * (beta_z * (anchor - Y) - Yd / omega)


def fit_weights(activations: np.ndarray, target: np.ndarray, method: str = "ridge",
                regularization: float = 1e-6) -> np.ndarray:
    """Weights ``W [D, d]`` from raw activations ``[L, D]`` and targets ``[L, d]``.

    ``regularization`` (ridge only) is relative to the mean diagonal of the normal matrix. A basis
    function that is never active gets weight 0 under either method.
    """
    if isinstance(regularization, bool) or not isinstance(regularization, (int, float, np.integer, np.floating)) \
            or not 0.0 <= regularization < np.inf:
        raise ValueError(f"regularization: expected a finite number >= 0, got {regularization!r}")
    if method == "lwr":
        mass = activations.sum(axis=0)                                          # [D]
        active = mass > 1e-12 * max(float(mass.max()), 1e-300)
        weights = np.zeros((activations.shape[1], target.shape[1]))
        weights[active] = (activations[:, active].T @ target) / mass[active, None]
        return weights
    if method == "ridge":
        normalized = normalize(activations)
        gram = normalized.T @ normalized
        lam = regularization * max(float(np.mean(np.diag(gram))), 1e-300)
        return np.linalg.solve(gram + lam * np.eye(gram.shape[0]), normalized.T @ target)
    raise ValueError(f"method: expected one of {FIT_METHODS}, got {method!r}")
