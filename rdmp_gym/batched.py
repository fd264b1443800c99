"""The forcing term (5) of B rollouts that each follow their own canonical path (perturbed initial conditions).

:meth:`BasisSet.forcing` evaluates one path at a time. Here all ``D`` log-activations of a rollout come
from one small matrix product: with the per-sample features

    F = [cos phi, sin phi, r^2, r cos phi, r sin phi, 1, log g(r), log a(r)]          [8, B, T]

the exponent of periodic function i is ``v_i cos c_i F_0 + v_i sin c_i F_1 - v_i F_5 + F_6`` and that of
transient function j is ``-vbar_j (F_2 - 2 q_j . (F_3, F_4) + |q_j|^2 F_5) + F_7`` (the same expanded
distance as ``BasisSet.activations``), so ``Psi = exp(C^T F)`` with a fixed ``C [8, D]``. A gate that
``BasisSet`` floors to exactly 0 gets the log ``-1500``, whose exponential is exactly 0 too. The weights
get one extra column of ones, so one product per rollout gives the numerator and the denominator of (5).
Rollouts are processed a few at a time so that the ``[T, D]`` blocks stay in the core's cache, and each
family's exponentials are evaluated only over the span of samples where its gate is not exactly 0 (along a
path r is monotonic: the periodic family is off during most of a long transient, the transient family is
off on the cycle); outside the span its activations are exactly 0, as in ``BasisSet.activations``.

The numbers equal those of ``BasisSet.forcing`` on each path to round-off (``tests/test_batched.py``).
"""

from __future__ import annotations

import numpy as np

from .basis import GATE_FLOOR, BasisSet, Fading

__all__ = ["batched_forcing", "exponent_matrix"]

_LOG_ZERO = -1500.0          # exp() of anything at or below this is exactly 0.0 in float64
_CHUNK_SAMPLES = 1024        # samples (x rollouts) per block: a [D, 1024] float64 block (640 KB for D = 80) stays in L2


def exponent_matrix(basis: BasisSet) -> np.ndarray:
    """``C [8, D]``: the log-activations of every basis function are ``F @ C`` (see the module docstring)."""
    n, m = basis.n_periodic, basis.transient_widths.size
    c, v = basis.periodic_centres, basis.periodic_widths
    q, vbar = basis.transient_centres, basis.transient_widths
    matrix = np.zeros((8, n + m))
    matrix[0, :n], matrix[1, :n], matrix[5, :n], matrix[6, :n] = v * np.cos(c), v * np.sin(c), -v, 1.0
    matrix[2, n:], matrix[3, n:], matrix[4, n:] = -vbar, 2.0 * vbar * q[:, 0], 2.0 * vbar * q[:, 1]
    matrix[5, n:], matrix[7, n:] = -vbar * np.sum(q**2, axis=1), 1.0
    return matrix


def _log_gate(fading: Fading, distance: np.ndarray) -> np.ndarray:
    """``log`` of a fade ``exp(-v_tilde distance^k)``, with ``_LOG_ZERO`` where ``Fading`` floors it to 0."""
    power = distance.copy()                       # distance**k (an int k) by multiplication: 10x faster than pow
    for _ in range(int(fading.k) - 1):
        power *= distance
    log_gate = -fading.v_tilde * power
    log_gate[log_gate < np.log(GATE_FLOOR)] = _LOG_ZERO
    return log_gate


def _features(fading: Fading, phi: np.ndarray, r: np.ndarray) -> np.ndarray:
    """``F [8, B, T]`` (feature-major, so every row is written contiguously) of canonical states ``phi, r [B, T]``."""
    features = np.empty((8, *phi.shape))
    np.cos(phi, out=features[0])
    np.sin(phi, out=features[1])
    np.multiply(r, r, out=features[2])
    np.multiply(r, features[0], out=features[3])
    np.multiply(r, features[1], out=features[4])
    features[5] = 1.0
    features[6] = _log_gate(fading, np.maximum(r - fading.mu1, 0.0))
    features[7] = _log_gate(fading, np.maximum(fading.mu2 - r, 0.0))
    return features


def batched_forcing(basis: BasisSet, phi: np.ndarray, r: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """The forcing term (5) of B rollouts, each on its own canonical path.

    Args:
        basis: the basis functions.
        phi, r: ``[B, T]`` canonical states of each rollout.
        weights: ``[B, d, D]`` weights of each rollout.
    Returns:
        ``[B, T, d]``, equal to ``basis.forcing(phi[b], r[b], weights[b])`` for every b to round-off.
    """
    phi, r = np.asarray(phi, dtype=float), np.asarray(r, dtype=float)
    weights = np.asarray(weights, dtype=float)
    if phi.ndim != 2 or r.shape != phi.shape:
        raise ValueError(f"phi, r: expected two arrays of the same shape [B, T], got {phi.shape} and {r.shape}")
    if weights.ndim != 3 or weights.shape[0] != phi.shape[0] or weights.shape[2] != basis.n_basis:
        raise ValueError(f"weights: expected shape [{phi.shape[0]}, d, {basis.n_basis}], got {weights.shape}")
    batch, samples = phi.shape
    dims, size = weights.shape[1], basis.n_basis
    matrix = np.ascontiguousarray(exponent_matrix(basis).T)                          # [D, 8]
    features = _features(basis.fading, phi, r).reshape(8, batch * samples)
    extended = np.concatenate([weights, np.ones((batch, 1, size))], axis=1)         # [B, d + 1, D]
    sums = np.empty((batch, dims + 1, samples))             # numerators [:, :d], denominator [:, d]
    families = ((slice(0, basis.n_periodic), 6), (slice(basis.n_periodic, size), 7))    # (rows, gate feature)
    step = max(1, _CHUNK_SAMPLES // max(samples, 1))
    for start in range(0, batch, step):
        count = min(step, batch - start)
        block = features[:, start * samples:(start + count) * samples]
        activation = np.zeros((size, count * samples))
        for rows, gate in families:     # only over the samples where the family's gate is not exactly 0
            live = np.flatnonzero(block[gate] > _LOG_ZERO)
            if live.size:
                span = slice(int(live[0]), int(live[-1]) + 1)
                np.exp(matrix[rows] @ block[:, span], out=activation[rows, span])
        np.matmul(extended[start:start + count], activation.reshape(size, count, samples).transpose(1, 0, 2),
                  out=sums[start:start + count])
    sums = sums.transpose(0, 2, 1)
    return sums[..., :dims] / (sums[..., dims:] + basis.fading.floor)
