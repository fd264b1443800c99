"""Imitation: the target forcing term (10) from a demonstration and the two regressions.

* ``lwr``: locally weighted regression exactly as the paper's (11)/(12): each weight is the
  activation-weighted mean of the target, one basis function at a time.
* ``ridge``: beyond the paper, one regularised least-squares problem on the normalised basis, so the
  mixture (5) itself (not each basis function separately) fits the target; all weights at once.
* ``trajectory`` (the default of :meth:`RhythmicDMP.fit`): beyond the paper, the weights and the start
  state that make the DMP's own rollout match the sampled positions, with a second-difference
  smoothness penalty on neighbouring weights. It needs no derivatives of the noisy samples: the
  target (10) multiplies position noise by ``alpha_z beta_z`` and the acceleration estimate amplifies it
  further, and every forcing error above the spring's bandwidth reaches the acceleration unfiltered.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.signal import savgol_filter

from .basis import NORMALISATION_EPSILON, normalize
from .validation import check_positive

__all__ = ["FIT_METHODS", "fit_trajectory", "fit_weights", "forcing_target", "second_differences", "smooth_derivatives"]

FIT_METHODS = ("lwr", "ridge", "trajectory")


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


def second_differences(sizes: Sequence[int], cyclic: Sequence[bool], spacings: Sequence[float],
                       reference: float) -> np.ndarray:
    """Second-difference operator ``[R, D]`` over consecutive families of ``sizes`` weights (D = sum).

    Row ``(w[i-1] - 2 w[i] + w[i+1]) (h_0 / h)^1.5`` for neighbours within one family (a cyclic family also
    wraps around), ``h`` the family's spacing in time and ``h_0 = reference``: the sum of squares then
    approximates the same integral of the squared second time derivative of the weights for every family,
    whatever its spacing or number of basis functions.
    """
    rows = []
    offset = 0
    for size, wraps, spacing in zip(sizes, cyclic, spacings, strict=True):
        centres = range(size) if wraps else range(1, size - 1)
        gain = (reference / spacing) ** 1.5
        for i in centres:
            row = np.zeros(sum(sizes))
            row[offset + (i - 1) % size] += gain
            row[offset + i] -= 2.0 * gain
            row[offset + (i + 1) % size] += gain
            rows.append(row)
        offset += size
    return np.array(rows).reshape(-1, sum(sizes))


def fit_weights(activations: np.ndarray, target: np.ndarray, method: str = "ridge",
                regularization: float = 1e-6, smoothness: float = 0.0,
                differences: np.ndarray | None = None, floor: float = NORMALISATION_EPSILON) -> np.ndarray:
    """Weights ``W [D, d]`` from raw activations ``[L, D]`` and forcing targets ``[L, d]`` (eq. (10)).

    ``regularization`` and ``smoothness`` (ridge only) penalise ``w`` and ``differences @ w`` (see
    :func:`second_differences`), relative to the mean diagonal of the normal matrix; ``floor`` is the
    mixture's (see :class:`~rdmp_gym.basis.Fading`). A basis function that is never active gets weight 0
    under either method.
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
        normalized = normalize(activations, floor)
        gram = normalized.T @ normalized
        scale = max(float(np.mean(np.diag(gram))), 1e-300)
        penalty = regularization * scale * np.eye(gram.shape[0])
        if smoothness > 0.0 and differences is not None:
            penalty = penalty + smoothness * scale * differences.T @ differences
        return np.linalg.solve(gram + penalty, normalized.T @ target)
    raise ValueError(f"method: expected one of {FIT_METHODS}, got {method!r}")


def fit_trajectory(responses: Sequence[np.ndarray], start_columns: Sequence[np.ndarray],
                   samples: Sequence[np.ndarray], differences: np.ndarray, smoothness: float,
                   regularization: float = 1e-8) -> tuple[np.ndarray, np.ndarray]:
    """Weights and start states that make the DMP's own rollout match the sampled positions.

    The rollout is linear in the weights and in each demonstration's start: ``y(t) = sum_b w_b R_b(t) +
    sum_c s_c S_c(t)`` (``R_b``: the path's response to basis function b alone, ``S_c``: to the start
    values ``s_c``). One penalised least-squares problem over all demonstrations gives the weights (shared)
    and each demonstration's start values (its own), without differentiating the noisy samples.

    Args:
        responses: per demonstration k, ``[L_k, D]`` responses to each basis function at its samples.
        start_columns: per demonstration, ``[L_k, C]`` responses to its C start values.
        samples: per demonstration, ``[L_k, d]`` positions minus the part the anchor explains.
        differences: ``[R, D]`` second-difference operator of :func:`second_differences`.
        smoothness, regularization: penalties on ``differences @ w`` and on ``w``, relative to the mean
            diagonal of the normal matrix of the weights.
    Returns:
        ``(W [D, d], starts [K, C, d])``.
    """
    n_basis, n_demos, n_start = responses[0].shape[1], len(samples), start_columns[0].shape[1]
    rows = []
    for k, (response, columns) in enumerate(zip(responses, start_columns, strict=True)):
        design = np.zeros((response.shape[0], n_basis + n_start * n_demos))
        design[:, :n_basis] = response
        design[:, n_basis + n_start * k: n_basis + n_start * (k + 1)] = columns
        rows.append(design)
    design, right = np.concatenate(rows), np.concatenate(samples)
    gram = design.T @ design
    scale = max(float(np.mean(np.diag(gram)[:n_basis])), 1e-300)
    penalty = np.zeros_like(gram)
    penalty[:n_basis, :n_basis] = scale * (smoothness * differences.T @ differences + regularization * np.eye(n_basis))
    solution = np.linalg.solve(gram + penalty, design.T @ right)
    return solution[:n_basis], solution[n_basis:].reshape(n_demos, n_start, -1)
