"""Errors of the agents layer that the command line reports (importable without the optional extras)."""

from __future__ import annotations

__all__ = ["NoValidEpisodesError", "WorkerError"]


class WorkerError(RuntimeError):
    """A worker (process or Ray actor) died while running episodes; the run's last checkpoint is intact."""


class NoValidEpisodesError(ValueError):
    """Every episode of the first update was invalid: the learner would only see a constant penalty."""
