"""The evaluation protocol: disjoint context sets, success, path smoothness, IQM with bootstrap intervals.

Contexts are reset seeds. Training draws its seeds from ``[0, 2**30)``; the validation set (for any
"best" selection and the held-out learning curves) and the test set (the final numbers) are fixed
seeds above that, disjoint from each other and from training:

    validation_seeds(n) = 2**30 + 500_000 + [0, n)        final_test_seeds(n) = 2**30 + [0, n)

What the protocol knows of a task it reads through the task's contract (:func:`rdmp_gym.envs.contract.contract_of`).

Success of an episode: ``info["is_success"]`` where the env reports it (its contract's ``has_success``); none is
made up where it does not (a task without success has no success rate).

Smoothness: the contract's measure of the executed path (the env's ``executed_path(action)`` at the contract's
``dt``): the integrated squared jerk ``∫ |d³y/dt³|² dt`` (third finite differences), or per integrated squared
speed (``speed_normalised_jerk``), relative to the imitation's in the same context.

Aggregates: the interquartile mean (``scipy.stats.trim_mean(x, 0.25)``) with a 95 % percentile
bootstrap interval (``scipy.stats.bootstrap``). ``rliable`` computes the same thing (its IQM is
``trim_mean`` too) but adds pandas, statsmodels, arch and seaborn (~160 MB) for these two scipy calls, and
its 1.2.0 release only imports with ``pandas<3`` (with pandas 3.1 arch 7.2 fails: ``TypeError:
deprecate_kwarg()``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from rdmp_gym.envs.contract import contract_of
from rdmp_gym.envs.smoothness import Smoothness
from scipy import stats

from rdmp_gym.synthetic.smoothness import integrated_squared_jerk

from .learners.base import EpisodeBatch

__all__ = [
    "TRAIN_SEED_LIMIT",
    "Interval",
    "PolicyScores",
    "context_observations",
    "defined_interval",
    "defined_mean",
    "evaluate_actions",
    "final_test_seeds",
    "interval",
    "iqm",
    "path_jerk",
    "stratified_validation_seeds",
    "success",
    "validation_seeds",
]

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

    The contract's ``context_kind(observation) -> str`` (e.g. the wiping task's cup on the approach, cup beside the
    patch, largest patch, no cup) sorts the first ``pool`` seeds of the validation range; the seeds are then taken
    from each kind in turn (kinds in the order they first appear, seeds in order), so a rare kind is represented
    as often as a common one. The choice depends on the env's contexts alone: it is made before any run and never
    touches the test seeds. A task that sorts its contexts into no kinds gives :func:`validation_seeds`.
    """
    count = _count(n, "n")
    kind_of = contract_of(env).context_kind
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


def success(batch: EpisodeBatch) -> np.ndarray | None:
    """``[K]`` success of each episode: the env's ``is_success`` (``batch.success``); None where the env does not
    report it (no success is made up from the task's metrics)."""
    return None if batch.success is None else np.asarray(batch.success, dtype=bool)


def defined_mean(values: np.ndarray) -> float:
    """The mean of ``values [K]`` over the episodes that have one (finite), NaN where none has (e.g. a metric of
    refused paths only)."""
    values = np.asarray(values, dtype=np.float64)
    defined = values[np.isfinite(values)]
    return float(np.mean(defined)) if defined.size else float("nan")


def path_smoothness(path: np.ndarray, measure: str, dt: float) -> float:
    """The smoothness ``measure`` (a contract's: ``"jerk"``, integrated squared jerk; ``"speed_normalised_jerk"``,
    per integrated squared speed) of ``path [T]`` or ``[T, d]`` sampled every ``dt`` s."""
    path = np.asarray(path, dtype=np.float64)
    path = path[:, None] if path.ndim == 1 else path
    if measure == "speed_normalised_jerk":
        return Smoothness.speed_normalised(path, dt)
    if measure == "jerk":
        return integrated_squared_jerk(path, dt)
    raise ValueError(f"measure: expected 'jerk' or 'speed_normalised_jerk', got {measure!r}")


def path_jerk(env: Any, action: np.ndarray, seed: int, options: dict[str, Any] | None = None) -> float:
    """The task's smoothness measure (its contract's ``smoothness``) of the path executed for ``action [n]`` in the
    context of ``seed`` (``env.unwrapped.executed_path``: e.g. with the wiping task's cup clearance where it is
    on): integrated squared jerk (m²/s⁵), or per integrated squared speed (1/s⁴, size-independent)."""
    env.reset(seed=int(seed), options=None if options is None else dict(options))
    contract = contract_of(env)
    path = env.unwrapped.executed_path(np.asarray(action, dtype=np.float64))
    return path_smoothness(path, contract.smoothness, contract.dt)


#: the per-context scores of :class:`PolicyScores` beside the task's metrics (a metric may not take these names)
_SCORES = ("seeds", "returns", "valid", "success", "jerk_ratio", "failures")


@dataclass(frozen=True)
class PolicyScores:
    """Per-context results of one policy on a context set (all ``[E]``).

    Attributes:
        seeds, returns, valid, jerk_ratio: the contexts' reset seeds, returns, validity and path smoothness relative
            to the imitation's.
        success: the env's ``is_success``, or None where the env does not report it.
        metrics: ``{key: [E]}`` the task's metrics (its contract's; NaN where a context has none).
        failures: the success criteria missed in each context (``""`` for a success), or None.
    """

    seeds: np.ndarray
    returns: np.ndarray
    valid: np.ndarray
    success: np.ndarray | None
    jerk_ratio: np.ndarray
    metrics: Mapping[str, np.ndarray] = field(default_factory=dict)
    failures: np.ndarray | None = None

    def __post_init__(self) -> None:
        clash = sorted(set(self.metrics) & set(_SCORES))
        if clash:
            raise ValueError(f"metrics: the task's metric keys {clash} are names of the scores {list(_SCORES)}")

    def means(self) -> dict[str, float]:
        """Mean of every score over the contexts (the numbers one seed contributes to a table): ``returns``, the
        task's metrics (over the contexts that have them), ``valid``, ``success`` (NaN where the env reports none)
        and ``jerk_ratio``."""
        success = np.nan if self.success is None else float(np.mean(self.success.astype(np.float64)))
        return {"returns": float(np.mean(self.returns.astype(np.float64))),
                **{key: defined_mean(values) for key, values in self.metrics.items()},
                "valid": float(np.mean(self.valid.astype(np.float64))), "success": success,
                "jerk_ratio": float(np.mean(self.jerk_ratio.astype(np.float64)))}

    def to_dict(self) -> dict[str, list | None]:
        """JSON-friendly lists: the scores and the task's metrics by their keys (None: not reported)."""
        scores = {name: getattr(self, name) for name in _SCORES}
        return {name: None if values is None else np.asarray(values).tolist()
                for name, values in {**scores, **self.metrics}.items()}


def evaluate_actions(evaluator: Any, actions: np.ndarray, seeds: np.ndarray, reference_jerk: np.ndarray | None = None
                     ) -> PolicyScores:
    """Run ``actions [E, n]`` in the contexts ``seeds [E]`` through ``evaluator.run`` (the one place that
    dispatches episodes) and measure their paths' smoothness relative to ``reference_jerk [E]`` (the
    imitation's; None: relative to the imitation computed here)."""
    actions = np.asarray(actions, dtype=np.float64)
    seeds = np.asarray(seeds, dtype=np.int64)
    batch = evaluator.run(actions, seeds)
    env, options = evaluator.env, evaluator.spec.options()
    jerk = np.array([path_jerk(env, a, s, options) for a, s in zip(actions, seeds, strict=True)])
    if reference_jerk is None:
        reference_jerk = np.array([path_jerk(env, np.zeros(actions.shape[1]), s, options) for s in seeds])
    return PolicyScores(seeds=seeds, returns=batch.returns, valid=batch.valid.astype(bool), success=success(batch),
                        jerk_ratio=jerk / np.maximum(reference_jerk, 1e-300), metrics=dict(batch.metrics),
                        failures=batch.failures)


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


def defined_interval(values: np.ndarray, statistic: str = "iqm") -> dict[str, float | int] | None:
    """:func:`interval` of the finite ``values [N]`` (``n`` of them) as a dict, None where none is finite (e.g. a
    timing error where no beat was counted)."""
    values = np.asarray(values, dtype=np.float64)
    defined = values[np.isfinite(values)]
    return interval(defined, statistic).to_dict() if defined.size else None
