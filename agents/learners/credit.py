"""What ``pi2``, the contextual searches and ``bbrl`` compute alike: PI²'s per-step credit and the weighted ridge fit.

**Per-step credit** (Theodorou et al. 2010): each rollout's cost-to-go ``S_k(t)`` (:func:`.base.cost_to_go`), less
a baseline, gives per-step weights ``P_k(t) ∝ exp(-h Â_k(t))`` over the rollouts (:func:`.base.cost_weights`); a
per-step quantity (those weights, PI²'s per-step update, a per-step fit) is then averaged over time per action
dimension by that dimension's time weights, so a dimension is judged by what followed while it acted.

**Weighted ridge fit**: the weighted maximum-likelihood (MAP) fit of targets on regressors ``[1, φ]``, pulled
towards the previous fit by a ridge (:func:`.base.ridge_penalty`, the constant column unpenalised).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .base import cost_to_go, cost_weights, ridge_penalty

__all__ = ["remaining_steps", "step_credit", "weighted_ridge"]


def remaining_steps(activation: np.ndarray) -> np.ndarray:
    """``[T, n]`` the activation ``[T, n]`` times the steps that remain, ``T - t`` (PI²'s averaging of its per-step
    updates: the steps whose cost-to-go covers most of the episode count most)."""
    steps = activation.shape[0]
    return (steps - np.arange(steps))[:, None] * activation


def step_credit(costs: np.ndarray, traces: np.ndarray, h: float, time_weights: np.ndarray, fallback: np.ndarray, *,
                hat: np.ndarray | None = None, offset: np.ndarray | None = None,
                per_step: Callable[[np.ndarray], np.ndarray] | None = None) -> np.ndarray:
    """PI²'s per-step credit of ``N`` rollouts, averaged over time per action dimension.

    Args:
        costs: ``[N]`` episode costs; traces: ``[N, T]`` their per-step parts.
        h: eliteness of the per-step weights.
        time_weights: ``[T, n]`` how much each action dimension counts at each step (its activation, or
            :func:`remaining_steps` of it).
        fallback: the result of a dimension whose time weights are all 0 (broadcastable to the result).
        hat: ``[N, N]`` a baseline's hat matrix (e.g. :func:`.base.ridge_hat` on the contexts): the cost-to-go less
            its fit, or None (the cost-to-go itself).
        offset: ``[N, T]`` (or ``[N, 1]``) a baseline subtracted from the cost-to-go first, or None.
        per_step: what is averaged: a map from the per-step weights ``[T, N]`` to a quantity per step and dimension,
            ``[T, n]`` (PI²'s update ``P @ ε``) or ``[T, n, F]`` (a per-step fit); None: the weights themselves.
    Returns:
        the time average per dimension, ``[n]`` or ``[n, F]``; without ``per_step`` ``[n, N]``, each dimension's
        weights of the rollouts (rows summing to 1).
    """
    to_go = cost_to_go(costs, traces)                                                   # [N, T]
    if offset is not None:
        to_go = to_go - offset
    weights = cost_weights((to_go if hat is None else to_go - hat @ to_go).T, h)       # [T, N]
    norm = time_weights.sum(axis=0)                                                     # [n]
    if per_step is None:
        total = time_weights.T @ weights                                                # [n, N]
    else:
        values = per_step(weights)                                                      # [T, n] or [T, n, F]
        total = ((time_weights * values).sum(axis=0) if values.ndim == 2
                 else np.einsum("tn,tnf->nf", time_weights, values))
    active = (norm > 0).reshape(norm.shape + (1,) * (total.ndim - 1))
    return np.where(active, total / np.where(active, norm.reshape(active.shape), 1.0), fallback)


def weighted_ridge(x: np.ndarray, weights: np.ndarray, targets: np.ndarray, previous: np.ndarray, prior: float, *,
                   per_dimension: bool = False) -> np.ndarray:
    """MAP fits ``argmin_W Σ_k w_k |y_k - W x_k|² + |(W - W_prev) Λ^½|²`` of targets on regressors ``x``.

    Args:
        x: ``[N, F]`` regressors ``[1, φ]`` of the ``N`` samples.
        weights: ``[S, N]`` sample weights, one row per fit; with ``per_dimension`` ``[n, N]``: row ``i`` weights
            the samples of target dimension ``i`` alone.
        targets: ``[N, n]`` what is fitted.
        previous: ``[n, F]`` the fit the ridge pulls towards.
        prior: the ridge ``Λ = diag(0, prior, ...)`` (:func:`.base.ridge_penalty`).
        per_dimension: each target dimension is fitted with its own row of ``weights``.
    Returns:
        ``[S, n, F]`` one fit of every target dimension per row of ``weights``; with ``per_dimension`` ``[n, F]``.
    """
    penalty = ridge_penalty(x.shape[1], prior)
    gram = np.einsum("sk,kf,kg->sfg", weights, x, x) + penalty                         # [S, F, F]
    if per_dimension:
        moment = np.einsum("ik,ki,kf->if", weights, targets, x) + previous @ penalty   # [n, F]
        return np.linalg.solve(gram, moment[..., None])[..., 0]
    moment = np.einsum("sk,kn,kf->snf", weights, targets, x) + previous @ penalty      # [S, n, F]
    return np.linalg.solve(gram, np.swapaxes(moment, 1, 2)).swapaxes(1, 2)
