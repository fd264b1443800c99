"""One episode as the agents see it: the return, the cost trace and the task's metrics, read through its contract.

An episode's numbers come from the env's ``step`` and its task contract (:func:`rdmp_gym.envs.contract.contract_of`):
the return and ``info["cost_trace"]`` (every episodic env's), the task's own metrics by their keys
(:func:`rdmp_gym.envs.contract.metric_values`: e.g. the wiping task's coverage, NaN where an episode has none),
validity, ``is_success`` where the env reports it and the success criteria missed where it names them.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from rdmp_gym.envs.contract import TaskContract, contract_of, metric_values

from .learners.base import EpisodeBatch

__all__ = ["episode_batch", "episode_metrics", "failure_contexts", "run_episode"]

#: joins an episode's ``info["failure_causes"]`` into the one string per episode the evaluation keeps
_FAILURE_JOIN = "+"


def episode_metrics(reward: float, info: Mapping[str, Any], contract: TaskContract) -> dict[str, Any]:
    """The numbers the agents use from one episodic ``step``.

    Returns:
        ``return``; ``cost_trace [T]``; ``metrics``: ``{key: value}`` of the contract's metrics (NaN where the
        episode has none); ``valid``; ``success``: ``info["is_success"]``, None where the env does not give it;
        ``failures``: the success criteria the episode missed (``info["failure_causes"]`` joined by ``"+"``, ``""``
        for a success), None where the env does not name them.
    """
    if "cost_trace" not in info:
        raise ValueError("info: the env returned no 'cost_trace' (per-control-step cost), which the agents need")
    return {"return": float(reward),
            "cost_trace": np.asarray(info["cost_trace"], dtype=np.float64),
            "metrics": metric_values(contract, info),
            "valid": bool(info.get("valid", True)),
            "success": None if "is_success" not in info else bool(info["is_success"]),
            "failures": None if "failure_causes" not in info else _FAILURE_JOIN.join(info["failure_causes"])}


def failure_contexts(failures: list[str]) -> dict[str, list[int]]:
    """``{cause: [index, ...]}``: where each success criterion was missed, from per-episode failures ``[E]``
    (:func:`episode_metrics`' ``failures``, e.g. the wiping task's ``"cup+coverage"``; ``""`` for a success), causes
    in first-seen order."""
    where: dict[str, list[int]] = {}
    for index, entry in enumerate(failures):
        for cause in filter(None, entry.split(_FAILURE_JOIN)):
            where.setdefault(cause, []).append(index)
    return where


def run_episode(env: Any, action: np.ndarray, seed: int, options: dict[str, Any] | None) -> dict[str, Any]:
    """One episode: reset with ``seed``, execute ``action [n]``; see :func:`episode_metrics` (the metrics of the
    env's contract)."""
    env.reset(seed=int(seed), options=options)
    _, reward, _, _, info = env.step(np.asarray(action, dtype=np.float32))
    return episode_metrics(reward, info, contract_of(env))


def episode_batch(actions: np.ndarray, results: Sequence[Mapping[str, Any]], seeds: np.ndarray,
                  contract: TaskContract) -> EpisodeBatch:
    """The :class:`~rdmp_gym.agents.learners.base.EpisodeBatch` of ``K`` episodes run with ``actions [K, n]`` and
    reset seeds ``seeds [K]``, from their :func:`episode_metrics` ``results`` (in the same order), with the metrics
    of the task's ``contract``."""
    if len(results) == 0 or len(results) != len(actions):
        raise ValueError(f"results: expected one per action ({len(actions)}), got {len(results)}")
    lengths = {result["cost_trace"].size for result in results}
    if len(lengths) != 1:
        raise ValueError(f"info['cost_trace']: episodes returned different lengths {sorted(lengths)}")
    success = [result["success"] for result in results]
    failures = [result["failures"] for result in results]
    return EpisodeBatch(actions=actions, returns=np.array([result["return"] for result in results]),
                        cost_traces=np.stack([result["cost_trace"] for result in results]),
                        valid=np.array([result["valid"] for result in results]), seeds=seeds,
                        metrics={key: np.array([result["metrics"][key] for result in results], dtype=np.float64)
                                 for key in contract.metric_keys},
                        success=None if None in success else np.array(success),
                        failures=None if None in failures else np.array(failures))
