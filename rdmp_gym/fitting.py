"""Imitation: the target forcing term (10) from a demonstration and the two regressions.

* ``lwr``: locally weighted regression exactly as the paper's (11)/(12): each weight is the
  activation-weighted mean of the target, one basis function at a time.
* ``ridge``: beyond the paper, one regularised least-squares problem on the normalised basis, so the
  mixture (5) itself (not each basis function separately) fits the target; all weights at once.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.signal import savgol_filter

from .basis import normalize
from .transformation import TransformationSystem

__all__ = ["FIT_METHODS", "fit_weights", "forcing_target", "smooth_derivatives"]

FIT_METHODS = ("lwr", "ridge", "trajectory")


def smooth_derivatives(Y: np.ndarray, dt: float, window: float, polyorder: int = 5
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Savitzky-Golay estimates of position, velocity and acceleration of ``Y [L, d]`` sampled every ``dt``.

    ``window`` is the filter length in seconds (rounded to an odd number of samples, at least
    ``polyorder + 2``). Returns three ``[L, d]`` arrays.
    """
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


def second_differences(sizes: tuple[int, ...], cyclic: tuple[bool, ...]) -> np.ndarray:
    """Second-difference operator ``[R, D]`` over consecutive families of ``sizes`` weights (D = sum).

    Row ``w[i-1] - 2 w[i] + w[i+1]`` for neighbours within one family; a cyclic family also wraps around.
    """
    rows = []
    offset = 0
    for size, wraps in zip(sizes, cyclic, strict=True):
        centres = range(size) if wraps else range(1, size - 1)
        for i in centres:
            row = np.zeros(sum(sizes))
            row[offset + (i - 1) % size] += 1.0
            row[offset + i] -= 2.0
            row[offset + (i + 1) % size] += 1.0
            rows.append(row)
        offset += size
    return np.array(rows).reshape(-1, sum(sizes))


def fit_weights(activations: np.ndarray, target: np.ndarray, method: str = "ridge",
                regularization: float = 1e-6, smoothness: float = 0.0,
                differences: np.ndarray | None = None) -> np.ndarray:
    """Weights ``W [D, d]`` from raw activations ``[L, D]`` and targets ``[L, d]``.

    ``regularization`` (ridge only) is relative to the mean diagonal of the normal matrix. A basis
    function that is never active gets weight 0 under either method.
    """
    if method == "lwr":
        mass = activations.sum(axis=0)                                          # [D]
        active = mass > 1e-12 * max(float(mass.max()), 1e-300)
        weights = np.zeros((activations.shape[1], target.shape[1]))
        weights[active] = (activations[:, active].T @ target) / mass[active, None]
        return weights
    if method == "ridge":
        normalized = normalize(activations)
        gram = normalized.T @ normalized
        scale = max(float(np.mean(np.diag(gram))), 1e-300)
        penalty = regularization * scale * np.eye(gram.shape[0])
        if smoothness > 0.0 and differences is not None:
            penalty = penalty + smoothness * scale * differences.T @ differences
        return np.linalg.solve(gram + penalty, normalized.T @ target)
    raise ValueError(f"method: expected one of {FIT_METHODS}, got {method!r}")


def fit_trajectory(normalized: Sequence[np.ndarray], samples: Sequence[np.ndarray], anchor: np.ndarray,
                   system: TransformationSystem, substeps: int, differences: np.ndarray,
                   smoothness: float, regularization: float = 1e-8) -> tuple[np.ndarray, np.ndarray]:
    """Weights and start states that make the DMP's own rollout match the sampled positions.

    The rollout is linear in the weights and the start state ``(y0, z0)``: for a fixed canonical path
    ``y(t) = sum_b w_b R_b(t) + S(t) g + E_y(t) y0 + E_z(t) z0``, where ``R_b`` is the spring's response to
    basis function b alone, ``S`` its response to the anchor and ``E`` the free response. One penalised
    least-squares problem over all demonstrations gives the weights (shared) and each demonstration's start
    (its own), without differentiating the noisy samples.

    Args:
        normalized: per demonstration, normalised activations ``[(L_k - 1) * substeps + 1, D]`` on a grid
            ``substeps`` times finer than its samples.
        samples: per demonstration, positions ``[L_k, d]``.
        anchor: ``[d]``.
        system: the transformation system discretised at the fine step.
        substeps: fine steps per sample.
        differences: ``[R, D]`` second-difference operator of :func:`second_differences`.
        smoothness, regularization: penalties on ``differences @ w`` and on ``w``, relative to the mean
            diagonal of the normal matrix of the weights.
    Returns:
        ``(W [D, d], starts [K, 2, d])`` with ``starts[k] = (y0, z0)``, ``z0 = yd0 / Omega``.
    """
    n_basis, n_demos = normalized[0].shape[1], len(samples)
    unit = np.array([[[1.0], [0.0]], [[0.0], [1.0]]])                                   # (y0, z0) unit states
    rows, right = [], []
    for k, (activation, Y) in enumerate(zip(normalized, samples, strict=True)):
        fine_times = np.arange(activation.shape[0]) * system.dt
        responses, _ = system.rollout(system.omega * activation, np.zeros(n_basis), np.zeros(n_basis))
        free, _ = system.free_response(fine_times, unit)                                # [2, Lf, 1]
        step, _ = system.rollout(system.input(np.ones(1), np.zeros((activation.shape[0], 1))),
                                 np.zeros(1), np.zeros(1))
        design = np.zeros((Y.shape[0], n_basis + 2 * n_demos))
        design[:, :n_basis] = responses[::substeps]
        design[:, n_basis + 2 * k: n_basis + 2 * k + 2] = free[:, ::substeps, 0].T
        rows.append(design)
        right.append(Y - step[::substeps] * anchor)
    design, right = np.concatenate(rows), np.concatenate(right)
    gram = design.T @ design
    scale = max(float(np.mean(np.diag(gram)[:n_basis])), 1e-300)
    penalty = np.zeros_like(gram)
    penalty[:n_basis, :n_basis] = scale * (smoothness * differences.T @ differences + regularization * np.eye(n_basis))
    solution = np.linalg.solve(gram + penalty, design.T @ right)
    return solution[:n_basis], solution[n_basis:].reshape(n_demos, 2, -1)
