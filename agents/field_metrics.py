"""Aggregate metrics of learners over seeds, as Agarwal et al. (NeurIPS 2021, "Deep RL at the edge of the
statistical precipice") recommend: interquartile means with **stratified bootstrap** intervals, performance
profiles and the probability of improvement.

Scores are ``[R, M]``: ``R`` runs (seeds) of one learner on ``M`` tasks (here: test contexts, or one column of
per-seed rates). The stratified bootstrap resamples the runs with replacement *within each task*, so every
task keeps its share. The bootstrap is scipy's; the reference implementation ``rliable`` is not a dependency
because its current release does not import with pandas 3.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .protocol import Interval, iqm

__all__ = ["curve_intervals", "performance_profile", "probability_of_improvement", "stratified_interval"]

_CONFIDENCE = 0.95


def _scores(values: np.ndarray, name: str) -> np.ndarray:
    scores = np.asarray(values, dtype=np.float64)
    if scores.ndim == 1:
        scores = scores[:, None]
    if scores.ndim != 2 or scores.size == 0:
        raise ValueError(f"{name}: expected scores [runs, tasks], got shape {np.shape(values)}")
    if not np.all(np.isfinite(scores)):
        raise ValueError(f"{name}: expected finite scores, got NaN or inf")
    return scores


def _resampled(scores: np.ndarray, statistic: Callable[[np.ndarray], np.ndarray | float], rng: np.random.Generator,
               resamples: int) -> np.ndarray:
    """``[B, ...]`` the statistic of ``B`` stratified bootstrap resamples of ``scores [R, M]``."""
    runs, tasks = scores.shape
    picks = rng.integers(0, runs, (resamples, runs, tasks))
    return np.array([statistic(np.take_along_axis(scores, pick, axis=0)) for pick in picks])


def stratified_interval(scores: np.ndarray, seed: int = 0, resamples: int = 2000) -> Interval:
    """IQM of all scores ``[R, M]`` (or ``[R]``) with a 95 % stratified percentile-bootstrap interval."""
    values = _scores(scores, "scores")
    estimate = iqm(values)
    if values.shape[0] == 1 or np.ptp(values) == 0:
        return Interval(estimate, estimate, estimate, values.shape[0])
    draws = _resampled(values, iqm, np.random.default_rng(seed), resamples)
    low, high = np.quantile(draws, [(1 - _CONFIDENCE) / 2, (1 + _CONFIDENCE) / 2])
    return Interval(estimate, float(low), float(high), values.shape[0])


def curve_intervals(curves: np.ndarray, seed: int = 0, resamples: int = 1000) -> np.ndarray:
    """Sample-efficiency curve: ``[P, 3]`` (IQM, low, high) over runs at each of ``P`` points of ``curves [R, P]``."""
    values = _scores(curves, "curves")
    rows = [stratified_interval(values[:, p], seed, resamples) for p in range(values.shape[1])]
    return np.array([[row.estimate, row.low, row.high] for row in rows])


def performance_profile(scores: np.ndarray, thresholds: np.ndarray, seed: int = 0,
                        resamples: int = 1000) -> np.ndarray:
    """``[len(thresholds), 3]``: the fraction of run-task scores above each threshold, with its 95 % interval."""
    values = _scores(scores, "scores")
    taus = np.asarray(thresholds, dtype=np.float64)

    def profile(sample: np.ndarray) -> np.ndarray:
        return np.mean(sample.ravel()[None, :] > taus[:, None], axis=1)

    estimate = profile(values)
    if values.shape[0] == 1:
        return np.c_[estimate, estimate, estimate]
    draws = _resampled(values, profile, np.random.default_rng(seed), resamples)
    low, high = np.quantile(draws, [(1 - _CONFIDENCE) / 2, (1 + _CONFIDENCE) / 2], axis=0)
    return np.c_[estimate, low, high]


def _improvement(x: np.ndarray, y: np.ndarray) -> float:
    """``P(X > Y)`` averaged over tasks (ties count one half): the Mann-Whitney statistic over ``m n``."""
    runs_x, runs_y = x[:, None, :], y[None, :, :]        # [R, 1, M], [1, R', M]: every task has R R' pairs
    return float(np.mean((runs_x > runs_y) + 0.5 * (runs_x == runs_y)))


def probability_of_improvement(x: np.ndarray, y: np.ndarray, seed: int = 0, resamples: int = 1000) -> Interval:
    """``P(X > Y)``: the probability that a run of learner X scores above a run of Y on a task, ``x [R, M]``,
    ``y [R', M]`` on the same ``M`` tasks, with a 95 % interval from stratified resamples of both."""
    first, second = _scores(x, "x"), _scores(y, "y")
    if first.shape[1] != second.shape[1]:
        raise ValueError(f"y: expected scores on the same {first.shape[1]} tasks as x, got {second.shape[1]}")
    estimate = _improvement(first, second)
    rng = np.random.default_rng(seed)
    draws = [_improvement(_resampled(first, lambda s: s, rng, 1)[0], _resampled(second, lambda s: s, rng, 1)[0])
             for _ in range(resamples)]
    low, high = np.quantile(draws, [(1 - _CONFIDENCE) / 2, (1 + _CONFIDENCE) / 2])
    return Interval(estimate, float(low), float(high), first.shape[0])
