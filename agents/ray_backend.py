"""Ray execution backend: episodes as tasks on Ray actors that each hold one environment (built once).

Used by :class:`rdmp_gym.agents.pool.Evaluator` with ``backend="ray"``. It joins the cluster at
``ray_address`` (or ``RAY_ADDRESS``) or, with neither, starts a local Ray instance with ``workers``
CPUs (and stops it again on ``close``). On a cluster every node needs ``rdmp-gym`` installed (the
actors import it) and any ``--demo`` file at the same path. Needs ``pip install 'rdmp-gym[ray]'``.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Sequence
from typing import Any

import numpy as np

from .errors import WorkerError
from .tasks import TaskSpec, run_episode

__all__ = ["EnvActor", "RayPool", "import_ray"]

logger = logging.getLogger(__name__)


def import_ray() -> Any:
    """The ``ray`` module, or an ImportError that says how to install it."""
    try:
        import ray
    except ImportError as error:
        raise ImportError("backend 'ray': ray is not installed; pip install 'rdmp-gym[ray]'") from error
    return ray


class EnvActor:
    """The state of one Ray actor: one environment of the task, built when the actor starts."""

    def __init__(self, spec: TaskSpec) -> None:
        self.env = spec.make()
        self.options = spec.options

    def episode(self, action: np.ndarray, seed: int) -> dict[str, Any]:
        """One episode (see :func:`rdmp_gym.agents.tasks.run_episode`)."""
        return run_episode(self.env, action, seed, self.options())

    def ping(self) -> int:
        """The actor's process id (a task that does no work: measures the per-task overhead)."""
        return os.getpid()


def init_ray(workers: int, address: str | None) -> bool:
    """Connect to ``address`` (or ``RAY_ADDRESS``), or start a local instance with ``workers`` CPUs; returns
    whether this call started Ray (and so should stop it). Reuses a Ray that is already initialised."""
    ray = import_ray()
    if ray.is_initialized():
        return False
    address = address or os.environ.get("RAY_ADDRESS") or None
    if address is not None:
        ray.init(address=address, logging_level=logging.WARNING, log_to_driver=False)
        logger.info("joined the Ray cluster at %s", address)
    else:
        ray.init(num_cpus=workers, include_dashboard=False, logging_level=logging.WARNING, log_to_driver=False)
        logger.info("started a local Ray instance with %d CPUs", workers)
    return True


class RayPool:
    """``workers`` :class:`EnvActor` actors (one CPU each); each actor has ``IN_FLIGHT`` episodes queued and gets
    the next one as it returns a result (results in submission order).

    Args:
        spec: the task.
        workers: actors.
        address: the Ray cluster (``auto``, ``ray://host:10001``, ...); default ``RAY_ADDRESS`` or a
            new local instance.
    """

    IN_FLIGHT = 2   #: episodes queued per actor

    def __init__(self, spec: TaskSpec, workers: int, address: str | None = None) -> None:
        ray = import_ray()

        self._owns = init_ray(workers, address)
        actor = ray.remote(num_cpus=1)(EnvActor)
        self.actors = [actor.remote(spec) for _ in range(workers)]
        logger.info("evaluating on %d Ray actors", workers)

    def map(self, actions: np.ndarray, seeds: Sequence[int]) -> list[dict[str, Any]]:
        """Ordered results of one episode per ``(action [n], seed)``."""
        from ray.exceptions import RayActorError

        ray = import_ray()
        jobs = list(zip(actions, seeds, strict=True))
        results: list[dict[str, Any] | None] = [None] * len(jobs)
        pending: dict[Any, tuple[int, Any]] = {}
        queued = iter(range(len(jobs)))

        def submit(actor: Any) -> None:
            index = next(queued, None)
            if index is not None:
                pending[actor.episode.remote(*jobs[index])] = (index, actor)

        try:
            for _ in range(self.IN_FLIGHT):      # a queued episode hides the round trip to the driver
                for actor in self.actors:
                    submit(actor)
            while pending:
                (done,), _ = ray.wait(list(pending), num_returns=1)
                index, actor = pending.pop(done)
                results[index] = ray.get(done)
                submit(actor)
            return results
        except RayActorError as error:
            raise WorkerError("evaluation: a Ray actor died (killed, node lost or out of memory); the run's last "
                              "checkpoint is intact: rerun with --resume to continue") from error

    def close(self) -> None:
        """Stop the actors (and the local Ray instance if this pool started it)."""
        ray = import_ray()
        for actor in self.actors:
            ray.kill(actor)
        self.actors = []
        if self._owns:
            ray.shutdown()
