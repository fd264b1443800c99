"""The forcing term (5) of B rollouts that each follow their own canonical path (perturbed initial conditions).

:meth:`BasisSet.forcing` evaluates one path at a time. Here the log-activations of a rollout come from
small matrix products: with the per-sample features

    F = [cos phi, sin phi, log g(r), 1, log a(r), r^2, r cos phi, r sin phi]          [8, T]

the exponent of periodic function i is ``v_i cos c_i F_0 + v_i sin c_i F_1 + F_2 - v_i F_3`` (rows 0-3) and
that of transient function j is ``-vbar_j (F_5 - 2 q_j . (F_6, F_7) + |q_j|^2 F_3) + F_4`` (rows 3-7, the
same expanded distance as ``BasisSet.activations``), so ``Psi = exp(C^T F)`` with a fixed ``C [8, D]``
(:func:`exponent_matrix`). A gate that ``BasisSet`` floors to exactly 0 gets the log ``-1500``. The weights
get one extra column of ones, so one product per rollout gives the numerator and the denominator of (5).

A periodic activation whose exponent is below ``log(floor) - 45`` is left at 0 instead of being exponentiated
(the periodic functions are narrow: about 14 of 40 are above it at any phase, and none where their gate is 0;
the transient ones are wide and all exponentiated). Leaving out D such terms moves the mixture
``sum Psi w / (sum Psi + floor)`` by at most ``2 D e^-45 max|w|`` (< 1e-17 max|w| for D = 80), below its own
round-off (about 1e-16 max|w|).

Rollouts are processed a few at a time (one at a time for T >= 1024; their features in bigger blocks) in
buffers that are reused, so the ``[D, T]`` blocks stay in the core's cache and no large temporaries are
allocated. The numbers equal those of ``BasisSet.forcing`` on each path to round-off (``tests/test_batched.py``).
"""

from __future__ import annotations

import numpy as np

from .basis import GATE_FLOOR, BasisSet, Fading

__all__ = ["NEGLIGIBLE_EXPONENT", "batched_forcing", "exponent_matrix"]

NEGLIGIBLE_EXPONENT = 45.0
"""Activations below ``exp(-NEGLIGIBLE_EXPONENT) * floor`` are left out of the mixture (see the module docstring)."""

_LOG_ZERO = -1500.0          # exp() of anything at or below this is exactly 0.0 in float64
_BLOCK_SAMPLES = 1024        # samples (x rollouts) per block of activations ([D, 1024] float64, 640 KB for D = 80)
_FEATURE_SAMPLES = 8192      # samples (x rollouts) per block of features ([8, 8192] float64, 512 KB)
_PERIODIC_ROWS, _TRANSIENT_ROWS = slice(0, 4), slice(3, 8)      # the features each family's exponents use


def exponent_matrix(basis: BasisSet) -> np.ndarray:
    """``C [8, D]``: the log-activations of every basis function are ``C^T F`` (see the module docstring)."""
    n, m = basis.n_periodic, basis.transient_widths.size
    c, v = basis.periodic_centres, basis.periodic_widths
    q, vbar = basis.transient_centres, basis.transient_widths
    matrix = np.zeros((8, n + m))
    matrix[0, :n], matrix[1, :n], matrix[2, :n], matrix[3, :n] = v * np.cos(c), v * np.sin(c), 1.0, -v
    matrix[3, n:], matrix[4, n:] = -vbar * np.sum(q**2, axis=1), 1.0
    matrix[5, n:], matrix[6, n:], matrix[7, n:] = -vbar, 2.0 * vbar * q[:, 0], 2.0 * vbar * q[:, 1]
    return matrix


def _log_gate(fading: Fading, distance: np.ndarray, out: np.ndarray) -> None:
    """``log`` of a fade ``exp(-v_tilde distance^k)`` into ``out``, ``_LOG_ZERO`` where ``Fading`` floors it to 0."""
    np.multiply(distance, distance, out=out)      # distance**k (an int k) by multiplication: 10x faster than pow
    for _ in range(int(fading.k) - 2):
        out *= distance
    if int(fading.k) == 1:
        out[...] = distance
    out *= -fading.v_tilde
    out[out < np.log(GATE_FLOOR)] = _LOG_ZERO


def _features(fading: Fading, phi: np.ndarray, r: np.ndarray, out: np.ndarray) -> None:
    """``F [8, S]`` (see the module docstring) of canonical states ``phi, r [S]`` into ``out``."""
    np.cos(phi, out=out[0])
    np.sin(phi, out=out[1])
    np.subtract(r, fading.mu1, out=out[5])
    np.maximum(out[5], 0.0, out=out[5])
    _log_gate(fading, out[5], out[2])
    out[3] = 1.0
    np.subtract(fading.mu2, r, out=out[5])
    np.maximum(out[5], 0.0, out=out[5])
    _log_gate(fading, out[5], out[4])
    np.multiply(r, r, out=out[5])
    np.multiply(r, out[0], out=out[6])
    np.multiply(r, out[1], out=out[7])


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
    dims, size, n = weights.shape[1], basis.n_basis, basis.n_periodic
    matrix = exponent_matrix(basis)
    periodic = np.ascontiguousarray(matrix[_PERIODIC_ROWS, :n].T)                  # [N, 4]
    transient = np.ascontiguousarray(matrix[_TRANSIENT_ROWS, n:].T)                # [M, 5]
    threshold = np.log(basis.fading.floor) - NEGLIGIBLE_EXPONENT
    extended = np.concatenate([weights, np.ones((batch, 1, size))], axis=1).transpose(0, 2, 1).copy()  # [B, D, d+1]
    result = np.empty((batch, samples, dims))
    phi_flat, r_flat = phi.reshape(-1), r.reshape(-1)
    step = max(1, min(batch, _BLOCK_SAMPLES // max(samples, 1)))           # rollouts per block of activations
    rows = step * max(1, min(batch, _FEATURE_SAMPLES // max(step * samples, 1)))   # ... per block of features
    features = np.empty((8, rows * samples))
    activation = np.empty((size, step * samples))
    exponents, live = np.empty((n, step * samples)), np.empty((n, step * samples), dtype=bool)    # periodic only
    sums = np.empty((step, samples, dims + 1))              # numerators [..., :d], denominator [..., d]
    for first in range(0, batch, rows):
        count = min(rows, batch - first)
        _features(basis.fading, phi_flat[first * samples:(first + count) * samples],
                  r_flat[first * samples:(first + count) * samples], features[:, :count * samples])
        for inner in range(0, count, step):                 # a [D, step * T] block at a time: it stays in cache
            size_k = min(step, count - inner)
            width, own = size_k * samples, features[:, inner * samples:(inner + size_k) * samples]
            # periodic: only the activations above the negligible level (about 14 of 40 at any phase)
            np.matmul(periodic, own[_PERIODIC_ROWS], out=exponents[:, :width])
            np.greater(exponents[:, :width], threshold, out=live[:, :width])
            activation[:n, :width] = 0.0
            np.exp(exponents[:, :width], out=activation[:n, :width], where=live[:, :width])
            # transient: wide functions, mostly above it (a masked exp would cost more than it saves), evaluated
            # over the span of samples where their gate is not exactly 0 (0 outside it, as in BasisSet.activations)
            gated = np.flatnonzero(own[4] > _LOG_ZERO)
            span = slice(int(gated[0]), int(gated[-1]) + 1) if gated.size else slice(0, 0)
            if span.stop - span.start < width:
                activation[n:, :width] = 0.0
            np.matmul(transient, own[_TRANSIENT_ROWS, span], out=activation[n:, span])
            np.exp(activation[n:, span], out=activation[n:, span])
            rollouts, block = slice(first + inner, first + inner + size_k), sums[:size_k]
            np.matmul(activation[:, :width].reshape(size, size_k, samples).transpose(1, 2, 0), extended[rollouts],
                      out=block)
            block[..., dims] += basis.fading.floor
            np.divide(block[..., :dims], block[..., dims:], out=result[rollouts])
    return result
