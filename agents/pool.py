"""Parallel evaluation of a population of episodes on an execution backend, one environment per worker.

Each episode is ``reset(seed=s, options=spec.reset_options)`` followed by one ``step(a)``; its outcome
depends only on ``(a, s)``, so a batch gives the same numbers with any backend and any number of
workers, in any order. A pool (rather than a vector env) runs batches of any size without wasted or
padded calls.

Backends:

* ``local`` (default): ``workers`` processes on this machine (``spawn``; 1 = in this process). A worker
  exits by itself within ``WATCHDOG_PERIOD`` seconds when the process that started it dies, so a
  ``kill -9`` of a run leaves no orphans; a worker that dies is a :class:`WorkerError`.
* ``ray``: ``workers`` Ray actors, each holding one environment built once (see
  :mod:`rdmp_gym.agents.ray_backend`), on a local Ray instance or a cluster (``ray_address`` or
  ``RAY_ADDRESS``). Needs the optional extra ``rdmp-gym[ray]``.
"""

from __future__ import annotations

import logging
import multiprocessing
import os
import threading
import time
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from types import TracebackType
from typing import Any, Protocol

import numpy as np
from rdmp_gym.envs.contract import TaskContract, contract_of

from .episodes import episode_batch, run_episode
from .errors import WorkerError
from .learners.base import EpisodeBatch
from .tasks import TaskSpec

__all__ = ["BACKENDS", "WATCHDOG_PERIOD", "Evaluator", "WorkerError", "run_episode", "watch_parent"]

logger = logging.getLogger(__name__)

BACKENDS = ("local", "ray")
WATCHDOG_PERIOD = 0.25
"""Seconds between a local worker's checks that the process that started it is alive."""

_WORKER: dict[str, Any] = {}


def watch_parent(parent: int) -> None:
    """Exit this process as soon as ``parent`` is no longer its parent (it died; we were re-parented)."""
    while os.getppid() == parent:
        time.sleep(WATCHDOG_PERIOD)
    os._exit(1)


def _start_worker(spec: TaskSpec, parent: int) -> None:
    threading.Thread(target=watch_parent, args=(parent,), daemon=True, name="parent-watchdog").start()
    _WORKER["env"] = spec.make()
    _WORKER["options"] = spec.options


def _worker_episode(action: np.ndarray, seed: int) -> dict[str, Any]:
    return run_episode(_WORKER["env"], action, seed, _WORKER["options"]())


class _Pool(Protocol):
    """What the evaluator needs from a backend: ordered results of one episode per ``(action, seed)``."""

    def map(self, actions: np.ndarray, seeds: Sequence[int]) -> list[dict[str, Any]]: ...

    def close(self) -> None: ...


class _ProcessPool:
    """``workers`` local worker processes (``spawn``: each one a direct child with its own env)."""

    def __init__(self, spec: TaskSpec, workers: int) -> None:
        self._executor = ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn"),
                                             initializer=_start_worker, initargs=(spec, os.getpid()))
        logger.info("evaluating on %d local worker processes", workers)

    def map(self, actions: np.ndarray, seeds: Sequence[int]) -> list[dict[str, Any]]:
        try:
            return list(self._executor.map(_worker_episode, actions, seeds))
        except BrokenProcessPool as error:
            raise WorkerError("evaluation: a worker process died (killed, or out of memory); the run's last "
                              "checkpoint is intact: rerun with --resume to continue") from error

    def close(self) -> None:
        self._executor.shutdown(cancel_futures=True)


class Evaluator:
    """Runs batches of episodes of one task on ``workers`` workers of a backend.

    Args:
        spec: the task.
        workers: worker processes (``local``; 1 runs the episodes here, one after the other) or Ray actors.
        backend: ``local`` or ``ray`` (see the module docstring).
        ray_address: the Ray cluster to join (``ray`` backend); default ``RAY_ADDRESS``, else a new local
            Ray instance with ``workers`` CPUs.

    ``env`` (built here too) gives the spaces, ``action_time_weights()``, the parameter mapping and the task's
    :attr:`contract`.
    Use as a context manager, or call :meth:`close`.
    """

    def __init__(self, spec: TaskSpec, workers: int = 1, backend: str = "local",
                 ray_address: str | None = None) -> None:
        if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
            raise ValueError(f"workers: expected a positive int, got {workers!r}")
        if backend not in BACKENDS:
            raise ValueError(f"backend: expected one of {BACKENDS}, got {backend!r}")
        if ray_address is not None and backend != "ray":
            raise ValueError("ray_address: only used with backend='ray'")
        self.spec = spec
        self.workers = workers
        self.backend = backend
        self.env = spec.make()
        self._pool: _Pool | None = None
        try:
            if backend == "ray":
                from .ray_backend import RayPool

                self._pool = RayPool(spec, workers, ray_address)
            elif workers > 1:
                self._pool = _ProcessPool(spec, workers)
        except BaseException:
            self.env.close()
            raise

    @property
    def contract(self) -> TaskContract:
        """The task's contract (:func:`rdmp_gym.envs.contract.contract_of` of :attr:`env`): what the batches, logs and
        reports may know of the task."""
        return contract_of(self.env)

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
            results = self._pool.map(actions, seeds.tolist())
        return episode_batch(actions, results, seeds, self.contract)

    def close(self) -> None:
        """Stop the workers and close the environment."""
        if self._pool is not None:
            self._pool.close()
            self._pool = None
        self.env.close()

    def __enter__(self) -> Evaluator:
        return self

    def __exit__(self, kind: type[BaseException] | None, value: BaseException | None,
                 traceback: TracebackType | None) -> None:
        self.close()
