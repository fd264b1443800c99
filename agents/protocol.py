"""The evaluation protocol: disjoint context sets, success, path smoothness, IQM with bootstrap intervals.

Contexts are reset seeds. Training draws its seeds from ``[0, 2**30)``; the validation set (for any
"best" selection and the held-out learning curves) and the test set (the final numbers) are fixed
seeds above that, disjoint from each other and from training:

    validation_seeds(n) = 2**30 + 500_000 + [0, n)        final_test_seeds(n) = 2**30 + [0, n)

Success of an episode: ``info["is_success"]`` where the env gives it; otherwise (ArmarWipe-v0) the same
definition, coverage >= 0.95 and force in band >= 0.9 of the wiping time and a valid (simulated) plan.

Smoothness: the integrated squared jerk ``∫ |d³y/dt³|² dt`` of the commanded path (the env's
``rollout_path`` at its control rate, third finite differences) relative to the imitation's in the same
context.

Aggregates: the interquartile mean (``scipy.stats.trim_mean(x, 0.25)``) with a 95 % percentile
bootstrap interval (``scipy.stats.bootstrap``). ``rliable`` computes the same thing (its IQM is
``trim_mean`` too) but adds pandas, statsmodels, arch and seaborn (~160 MB) for these two scipy calls, and
its 1.2.0 release only imports with ``pandas<3`` (with pandas 3.1 arch 7.2 fails: ``TypeError:
deprecate_kwarg()``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from rdmp_gym.envs.smoothness import Smoothness
from scipy import stats

from rdmp_gym.synthetic.smoothness import integrated_squared_jerk

from .learners.base import EpisodeBatch

__all__ = [
    "COVERAGE_TARGET",
    "FORCE_TARGET",
    "TRAIN_SEED_LIMIT",
    "Interval",
    "PolicyScores",
    "context_observations",
    "evaluate_actions",
    "final_test_seeds",
    "interval",
    "iqm",
    "path_jerk",
    "stratified_validation_seeds",
    "success",
    "validation_seeds",
]

COVERAGE_TARGET, FORCE_TARGET = 0.95, 0.90
TRAIN_SEED_LIMIT = 2**30
_VALIDATION_OFFSET = 500_000


def _count(n: int, name: str) -> int:
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1 or n > _VALIDATION_OFFSET:
        raise ValueError(f"{name}: expected an int in [1, {_VALIDATION_OFFSET}], got {n!r}")
    return int(n)


def final_test_seeds(n: int) -> np.ndarray:
    """``[n]`` the reset seeds of the test contexts (never used in training or selection)."""
    return TRAIN_SEED_LIMIT + np.arange(_count(n, "n"), dtype=np.int64)


def validation_seeds(n: int) -> np.ndarray:
    """``[n]`` the reset seeds of the validation contexts (selection and learning curves)."""
    return TRAIN_SEED_LIMIT + _VALIDATION_OFFSET + np.arange(_count(n, "n"), dtype=np.int64)


def stratified_validation_seeds(env: Any, n: int, options: dict[str, Any] | None = None, pool: int = 400
                                ) -> np.ndarray:
    """``[n]`` validation reset seeds spread evenly over the kinds of context the env names.

    The env's ``context_kind(observation) -> str`` (e.g. the wiping task's cup on the approach, cup beside the
    patch, largest patch, no cup) sorts the first ``pool`` seeds of the validation range; the seeds are then taken
    from each kind in turn (kinds in the order they first appear, seeds in order), so a rare kind is represented
    as often as a common one. The choice depends on the env's contexts alone: it is made before any run and never
    touches the test seeds. An env without ``context_kind`` gives :func:`validation_seeds`.
    """
    count = _count(n, "n")
    kind_of = getattr(getattr(env, "unwrapped", env), "context_kind", None)
    if kind_of is None:
        return validation_seeds(count)
    by_kind: dict[str, list[int]] = {}
    for seed in validation_seeds(max(_count(pool, "pool"), count)):
        observation = env.reset(seed=int(seed), options=None if options is None else dict(options))[0]
        by_kind.setdefault(str(kind_of(observation)), []).append(int(seed))
    queues = list(by_kind.values())
    chosen: list[int] = []
    while len(chosen) < count:
        for queue in queues:
            if queue and len(chosen) < count:
                chosen.append(queue.pop(0))
    return np.array(sorted(chosen), dtype=np.int64)


def context_observations(env: Any, seeds: np.ndarray, options: dict[str, Any] | None = None) -> np.ndarray:
    """``[E, o]`` the observations (contexts) of reset seeds ``[E]``."""
    return np.stack([np.asarray(env.reset(seed=int(s), options=None if options is None else dict(options))[0],
                                dtype=np.float64) for s in seeds])


def success(batch: EpisodeBatch) -> np.ndarray:
    """``[K]`` success of each episode: ``batch.success`` (the env's ``is_success``) if known, else
    coverage >= 0.95, force in band >= 0.9 and valid (NaN coverage counts as failure)."""
    if batch.success is not None:
        return np.asarray(batch.success, dtype=bool)
    with np.errstate(invalid="ignore"):
        return ((np.nan_to_num(batch.coverage, nan=-1.0) >= COVERAGE_TARGET)
                & (np.nan_to_num(batch.force_in_band, nan=-1.0) >= FORCE_TARGET) & batch.valid.astype(bool))


def path_jerk(env: Any, action: np.ndarray, seed: int, options: dict[str, Any] | None = None) -> float:
    """The task's jerk measure of the path executed for ``action [n]`` in the context of ``seed`` (with the
    env's clearance term where it has one on): integrated squared jerk (m²/s⁵), or per integrated squared speed
    (1/s⁴, size-independent) where the task's smoothness term uses that (``task_version.speed_normalised_jerk``,
    ``ArmarWipe-v2``)."""
    env.reset(seed=int(seed), options=None if options is None else dict(options))
    base = env.unwrapped
    task = getattr(base, "task", None)
    if hasattr(task, "executed_path"):        # a task that may change the planned path before executing it
        path = task.executed_path(base.action_to_params(np.asarray(action, dtype=np.float64)), base.context)
    elif hasattr(base, "action_path"):        # an env whose path depends on more than the DMP's parameters
        path = base.action_path(np.asarray(action, dtype=np.float64))
    else:
        path = base.rollout_path(base.action_to_params(np.asarray(action, dtype=np.float64)))
    dt = float(getattr(base, "dt", 0.0) or 1.0)   # an env without ``dt``: unit steps (ratios are unaffected)
    version = getattr(base, "task_version", None)
    if version is not None and version.speed_normalised_jerk:
        return Smoothness.speed_normalised(path, dt)
    return integrated_squared_jerk(path, dt)


@dataclass(frozen=True)
class PolicyScores:
    """Per-context results of one policy on a context set (all ``[E]``)."""

    seeds: np.ndarray
    returns: np.ndarray
    coverage: np.ndarray
    force_in_band: np.ndarray
    valid: np.ndarray
    success: np.ndarray
    jerk_ratio: np.ndarray
    #: the success criteria missed in each context (``"cup+coverage"``, ``""`` for a success), or None
    failures: np.ndarray | None = None

    def means(self) -> dict[str, float]:
        """Mean of every metric over the contexts (the numbers one seed contributes to a table)."""
        return {name: float(np.mean(getattr(self, name).astype(np.float64)))
                for name in ("returns", "coverage", "force_in_band", "valid", "success", "jerk_ratio")}

    def to_dict(self) -> dict[str, list]:
        """JSON-friendly lists."""
        return {name: np.asarray(getattr(self, name)).tolist() for name in self.__dataclass_fields__}


def evaluate_actions(evaluator: Any, actions: np.ndarray, seeds: np.ndarray, reference_jerk: np.ndarray | None = None
                     ) -> PolicyScores:
    """Run ``actions [E, n]`` in the contexts ``seeds [E]`` through ``evaluator.run`` (the one place that
    dispatches episodes) and measure their paths' jerk relative to ``reference_jerk [E]`` (the
    imitation's; None: relative to the imitation computed here)."""
    actions = np.asarray(actions, dtype=np.float64)
    seeds = np.asarray(seeds, dtype=np.int64)
    batch = evaluator.run(actions, seeds)
    env, options = evaluator.env, evaluator.spec.options()
    jerk = np.array([path_jerk(env, a, s, options) for a, s in zip(actions, seeds, strict=True)])
    if reference_jerk is None:
        reference_jerk = np.array([path_jerk(env, np.zeros(actions.shape[1]), s, options) for s in seeds])
    return PolicyScores(seeds=seeds, returns=batch.returns, coverage=batch.coverage, force_in_band=batch.force_in_band,
                        valid=batch.valid.astype(bool), success=success(batch),
                        jerk_ratio=jerk / np.maximum(reference_jerk, 1e-300), failures=batch.failures)


def iqm(values: np.ndarray) -> float:
    """Interquartile mean of ``values [N]`` (the mean of the middle 50 %; of all of them for ``[R, M]``)."""
    return float(stats.trim_mean(np.asarray(values, dtype=np.float64).ravel(), 0.25))


@dataclass(frozen=True)
class Interval:
    """A point estimate with its 95 % bootstrap interval."""

    estimate: float
    low: float
    high: float
    n: int

    def to_dict(self) -> dict[str, float | int]:
        return {"estimate": self.estimate, "low": self.low, "high": self.high, "n": self.n}

    def __str__(self) -> str:
        return f"{self.estimate:.3f} [{self.low:.3f}, {self.high:.3f}]"


def interval(values: np.ndarray, statistic: str = "iqm", seed: int = 0, resamples: int = 2000) -> Interval:
    """``statistic`` (``iqm`` or ``mean``) of ``values [N]`` (e.g. one number per seed) with a 95 %
    percentile-bootstrap interval; a constant sample (or N = 1) gives a zero-width interval."""
    values = np.asarray(values, dtype=np.float64).ravel()
    if values.size == 0 or not np.all(np.isfinite(values)):
        raise ValueError(f"values: expected finite numbers, got {values.size} values with NaN or inf")
    if statistic not in ("iqm", "mean"):
        raise ValueError(f"statistic: expected 'iqm' or 'mean', got {statistic!r}")
    function = iqm if statistic == "iqm" else (lambda x: float(np.mean(x)))
    estimate = function(values)
    if values.size == 1 or np.ptp(values) == 0:
        return Interval(estimate, estimate, estimate, int(values.size))

    def vectorised(sample: np.ndarray, axis: int = -1) -> np.ndarray:
        if statistic == "iqm":
            return stats.trim_mean(sample, 0.25, axis=axis)
        return np.mean(sample, axis=axis)

    result = stats.bootstrap((values,), vectorised, n_resamples=resamples, confidence_level=0.95,
                             method="percentile", vectorized=True, rng=np.random.default_rng(seed))
    return Interval(estimate, float(result.confidence_interval.low), float(result.confidence_interval.high),
                    int(values.size))
