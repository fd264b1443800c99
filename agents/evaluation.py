"""Parallel evaluation of a population of episodes: a process pool with one environment per worker.

Each episode is ``reset(seed=s, options=spec.reset_options)`` followed by one ``step(a)``; its outcome
depends only on ``(a, s)``, so a batch gives the same numbers with any number of workers, in any order.
A pool (rather than a vector env) runs batches of any size without wasted or padded calls.
"""

from __future__ import annotations

import logging
import multiprocessing
from concurrent.futures import ProcessPoolExecutor
from types import TracebackType
from typing import Any

import gymnasium as gym
import numpy as np

from .learners.base import EpisodeBatch
from .tasks import TaskSpec, episode_metrics

__all__ = ["Evaluator", "run_episode"]

logger = logging.getLogger(__name__)

_WORKER: dict[str, Any] = {}


def run_episode(env: gym.Env, action: np.ndarray, seed: int, options: dict[str, Any] | None
                ) -> dict[str, Any]:
    """One episode: reset with ``seed``, execute ``action [n]``; see :func:`episode_metrics`."""
    env.reset(seed=int(seed), options=options)
    _, reward, _, _, info = env.step(np.asarray(action, dtype=np.float32))
    return episode_metrics(reward, info)


def _start_worker(spec: TaskSpec) -> None:
    _WORKER["env"] = spec.make()
    _WORKER["options"] = spec.options


def _worker_episode(action: np.ndarray, seed: int) -> dict[str, Any]:
    return run_episode(_WORKER["env"], action, seed, _WORKER["options"]())


class Evaluator:
    """Runs batches of episodes of one task on ``workers`` processes (1 = in this process).

    Args:
        spec: the task.
        workers: worker processes; 1 runs the episodes here, one after the other.

    ``env`` (built here too) gives the spaces, ``action_time_weights()`` and parameter mapping.
    Use as a context manager, or call :meth:`close`.
    """

    def __init__(self, spec: TaskSpec, workers: int = 1) -> None:
        if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
            raise ValueError(f"workers: expected a positive int, got {workers!r}")
        self.spec = spec
        self.workers = workers
        self.env = spec.make()
        self._pool: ProcessPoolExecutor | None = None
        if workers > 1:
            method = "forkserver" if "forkserver" in multiprocessing.get_all_start_methods() else "spawn"
            self._pool = ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context(method),
                                             initializer=_start_worker, initargs=(spec,))
            logger.info("evaluating on %d %s worker processes", workers, method)

    @property
    def n_actions(self) -> int:
        """Dimension of the action space."""
        return int(self.env.action_space.shape[0])

    def run(self, actions: np.ndarray, seeds: np.ndarray) -> EpisodeBatch:
        """Evaluate ``actions [K, n]`` with reset seeds ``seeds [K]``."""
        actions = np.asarray(actions, dtype=np.float64)
        seeds = np.asarray(seeds, dtype=np.int64)
        if actions.ndim != 2 or actions.shape[1] != self.n_actions:
            raise ValueError(f"actions: expected shape [K, {self.n_actions}], got {actions.shape}")
        if seeds.shape != (actions.shape[0],):
            raise ValueError(f"seeds: expected {actions.shape[0]} seeds, got shape {seeds.shape}")
        if self._pool is None:
            results = [run_episode(self.env, a, s, self.spec.options()) for a, s in zip(actions, seeds, strict=True)]
        else:
            results = list(self._pool.map(_worker_episode, actions, seeds.tolist()))
        lengths = {r["cost_trace"].size for r in results}
        if len(lengths) != 1:
            raise ValueError(f"info['cost_trace']: episodes returned different lengths {sorted(lengths)}")
        return EpisodeBatch(actions=actions, returns=np.array([r["return"] for r in results]),
                            cost_traces=np.stack([r["cost_trace"] for r in results]),
                            coverage=np.array([r["coverage"] for r in results]),
                            force_in_band=np.array([r["force_in_band"] for r in results]),
                            valid=np.array([r["valid"] for r in results]), seeds=seeds,
                            success=None if any(r["success"] is None for r in results)
                            else np.array([r["success"] for r in results]))

    def close(self) -> None:
        """Stop the workers and close the environment."""
        if self._pool is not None:
            self._pool.shutdown()
            self._pool = None
        self.env.close()

    def __enter__(self) -> Evaluator:
        return self

    def __exit__(self, kind: type[BaseException] | None, value: BaseException | None,
                 traceback: TracebackType | None) -> None:
        self.close()
