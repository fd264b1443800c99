"""The task contract: what the tools (learners, evaluation, logs, report, plots) may know of a task.

An episodic env of this package declares its contract through one method, ``env.unwrapped.task_contract()``: the
face of a task description (:class:`~rdmp_gym.envs.rhythmic_env.RhythmicTaskEnv`) from the task's declaration, the
black-box wrapper (:class:`~rdmp_gym.envs.blackbox.RhythmicBlackBoxWrapper`) for a foreign env. The tools read a
task through :func:`contract_of` and nothing else: they never name a task's info keys, and they never reach into
the task through the env.

A contract holds:

- the task's **metrics**: per episode, a number read from ``info`` under its key (coverage for wiping, the struck
  fraction and the timing error for drumming, the episode length and the tracking error for a foreign env); the
  return is every task's and is not listed;
- the **context**: the observation's named fields (``{name: (start, size)}``) and, where the task sorts its
  contexts into kinds, ``context_kind(observation) -> str``;
- **success**: whether the env reports ``info["is_success"]`` (no success is made up where it does not);
- the **smoothness** measure of an executed path (``"jerk"``: integrated squared jerk; ``"speed_normalised_jerk"``:
  per unit of integrated squared speed) and the path's step ``dt``;
- the **executed path**: ``env.unwrapped.executed_path(action) -> [T, d]`` in the current episode's context, the
  path the plots draw and the smoothness is measured on (``path_labels`` name its columns).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

__all__ = ["SMOOTHNESS", "Metric", "TaskContract", "contract_of", "metric_values"]

#: the smoothness measures a contract may name
SMOOTHNESS = ("jerk", "speed_normalised_jerk")


@dataclass(frozen=True)
class Metric:
    """One per-episode number of a task.

    Attributes:
        key: the ``info`` key it is read from, also its name in logs and results.
        label: how tables and figures name it (e.g. "timing error"; default: the key with spaces).
        higher_is_better: its direction (False for an error).
        unit: its unit, "" where it has none.
    """

    key: str
    label: str = ""
    higher_is_better: bool = True
    unit: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.key, str) or not self.key.isidentifier():
            raise ValueError(f"key: expected an identifier (an info key), got {self.key!r}")
        if not self.label:
            object.__setattr__(self, "label", self.key.replace("_", " "))


@dataclass(frozen=True)
class TaskContract:
    """What the tools may know of a task; see the module docstring.

    Attributes:
        name: the task's name (``"wipe"``, ``"drum"``, or a foreign env's id).
        metrics: the task's per-episode metrics, in the order tables show them.
        context_fields: ``{field: (start, size)}`` of the observation (empty: unnamed).
        has_success: whether ``info["is_success"]`` is reported.
        smoothness: ``"jerk"`` or ``"speed_normalised_jerk"`` of the executed path.
        dt: the executed path's step (s).
        path_labels: the executed path's column names (``("x", "y", "z")``; a joint path: the joints).
        context_kind: ``observation [o] -> kind`` (e.g. the wiping task's ``"cup on the approach"``), or None.
    """

    name: str
    metrics: tuple[Metric, ...] = ()
    context_fields: Mapping[str, tuple[int, int]] = field(default_factory=dict)
    has_success: bool = False
    smoothness: Literal["jerk", "speed_normalised_jerk"] = "jerk"
    dt: float = 1.0
    path_labels: tuple[str, ...] = ()
    context_kind: Callable[[np.ndarray], str] | None = None

    def __post_init__(self) -> None:
        if self.smoothness not in SMOOTHNESS:
            raise ValueError(f"smoothness: expected one of {SMOOTHNESS}, got {self.smoothness!r}")
        if not (np.isfinite(self.dt) and self.dt > 0):
            raise ValueError(f"dt: expected a step > 0 s, got {self.dt!r}")
        keys = [metric.key for metric in self.metrics]
        if len(set(keys)) != len(keys) or {"return", "is_success"} & set(keys):
            raise ValueError(f"metrics: expected distinct keys other than 'return' and 'is_success', got {keys}")
        for name, entry in self.context_fields.items():
            if len(entry) != 2 or int(entry[0]) < 0 or int(entry[1]) < 1:
                raise ValueError(f"context_fields: {name!r} needs (start >= 0, size >= 1), got {entry!r}")

    @property
    def metric_keys(self) -> tuple[str, ...]:
        """The metrics' keys, in order."""
        return tuple(metric.key for metric in self.metrics)

    def metric(self, key: str) -> Metric:
        """The metric of ``key`` (ValueError naming the task's metrics if it has none of that key)."""
        for metric in self.metrics:
            if metric.key == key:
                return metric
        raise ValueError(f"metric: {self.name} has the metrics {list(self.metric_keys)}, not {key!r}")


def metric_values(contract: TaskContract, info: Mapping[str, Any]) -> dict[str, float]:
    """``{key: value}`` of the contract's metrics in one episode's ``info`` (NaN where the episode has none, e.g. a
    path refused before it was simulated)."""
    values = {}
    for key in contract.metric_keys:
        value = info.get(key)
        values[key] = float(value) if isinstance(value, (int, float, np.integer, np.floating)) else float("nan")
    return values


def contract_of(env: Any) -> TaskContract:
    """The contract of an episodic env (or a wrapper of one): ``env.unwrapped.task_contract()``.

    Raises:
        ValueError: the env declares none (it is not an episodic env of this package; a step-based Gymnasium env
            runs under the black-box wrapper, which declares one).
    """
    base = getattr(env, "unwrapped", env)
    declare = getattr(type(base), "task_contract", None)
    if declare is None:
        raise ValueError(f"env: {type(base).__name__} declares no task contract (task_contract()); wrap a step-based "
                         f"env with rdmp_gym.envs.blackbox.make_blackbox")
    contract = declare(base)
    if not isinstance(contract, TaskContract):
        raise TypeError(f"env: {type(base).__name__}.task_contract() returned {type(contract).__name__}, "
                        f"not a TaskContract")
    return contract
