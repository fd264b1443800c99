"""The tasks of rdmp-gym: a registry of :class:`~rdmp_gym.envs.tasks.description.TaskDescription` by name.

Adding a task is one folder with its description and one line in :data:`TASKS` (or a call of :func:`register_task`
from user code); :mod:`rdmp_gym.envs.registration` gives every task x robot its ids.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from .description import Outcome, TaskDescription, TaskPlan, ToolPath
from .drumming import DrumTask

__all__ = ["TASKS", "Outcome", "TaskDescription", "TaskPlan", "ToolPath", "get_task", "register_task"]

#: name -> factory (keywords: the task's settings) of every task on the rhythmic face
TASKS: dict[str, Callable[..., TaskDescription]] = {"drum": DrumTask}


def register_task(name: str, factory: Callable[..., TaskDescription]) -> None:
    """Make a task available by ``name`` (an existing name is replaced); ``factory(**settings)`` builds it."""
    if not callable(factory):
        raise TypeError(f"factory: expected a TaskDescription class or factory, got {type(factory).__name__}")
    TASKS[name] = factory


def get_task(task: str | TaskDescription, **settings: Any) -> TaskDescription:
    """The description of ``task`` (a registered name built with ``settings``, or a description as it is)."""
    if isinstance(task, TaskDescription):
        if settings:
            raise ValueError(f"{sorted(settings)}: settings go to a task given by name, not to a description")
        return task
    if task not in TASKS:
        raise ValueError(f"task: expected one of {sorted(TASKS)} or a TaskDescription, got {task!r}")
    return TASKS[task](**settings)
