"""The tasks of rdmp-gym's rhythmic face: a registry of task descriptions by name.

A task is one folder with its :class:`~rdmp_gym.envs.tasks.description.TaskDescription` and one line in
:data:`TASKS`: its name, the part of its env ids, its versions and where its description lives (imported on first
use, so that registering the ids imports no MuJoCo). :mod:`rdmp_gym.envs.registration` gives every task x robot its
ids ``rdmp_gym/{Robot}{Task}-v{N}`` and ``rdmp_gym/{Robot}{Task}Step-v{N}``; :func:`register_task` adds a task from
user code (and :func:`rdmp_gym.envs.registration.register_task_ids` its ids).
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Any

from .description import Outcome, TaskDescription, TaskPlan, ToolPath

__all__ = ["TASKS", "Outcome", "TaskDescription", "TaskEntry", "TaskPlan", "ToolPath", "get_task", "register_task"]


@dataclass(frozen=True)
class TaskEntry:
    """A registered task: ``id_name`` (its part of the env ids), ``versions`` and ``factory`` (a
    ``"module:attribute"`` string or a callable building the description from its settings)."""

    id_name: str
    versions: tuple[int, ...]
    factory: Any

    def build(self, **settings: Any) -> TaskDescription:
        """The description with ``settings``."""
        return self._factory()(**settings)

    def learner_defaults(self) -> dict[str, dict[str, Any]]:
        """The task's :attr:`~rdmp_gym.envs.tasks.description.TaskDescription.learner_defaults` (empty where the
        factory is not a description class)."""
        factory = self._factory()
        defaults = getattr(factory, "learner_defaults", {}) if isinstance(factory, type) else {}
        return {agent: dict(options) for agent, options in defaults.items()}

    def _factory(self) -> Any:
        if isinstance(self.factory, str):
            module, attribute = self.factory.split(":")
            return getattr(importlib.import_module(module), attribute)
        return self.factory


#: name -> entry of every task on the rhythmic face
TASKS: dict[str, TaskEntry] = {
    "drum": TaskEntry("Drum", (1,), "rdmp_gym.envs.tasks.drumming:DrumTask"),
}


def register_task(name: str, factory: Any, id_name: str | None = None, versions: tuple[int, ...] = (1,)) -> None:
    """Make a task available by ``name`` (an existing name is replaced); ``factory(**settings)`` builds its
    description (a class, a callable or a ``"module:attribute"`` string)."""
    if not (callable(factory) or isinstance(factory, str)):
        raise TypeError(f"factory: expected a TaskDescription class, a callable or 'module:attribute', got "
                        f"{type(factory).__name__}")
    TASKS[name] = TaskEntry(id_name or name.capitalize(), tuple(versions), factory)


def get_task(task: str | TaskDescription, **settings: Any) -> TaskDescription:
    """The description of ``task`` (a registered name built with ``settings``, or a description as it is)."""
    if isinstance(task, TaskDescription):
        if settings:
            raise ValueError(f"{sorted(settings)}: settings go to a task given by name, not to a description")
        return task
    if task not in TASKS:
        raise ValueError(f"task: expected one of {sorted(TASKS)} or a TaskDescription, got {task!r}")
    description = TASKS[task].build(**settings)
    if not isinstance(description, TaskDescription):
        raise TypeError(f"task: the factory of {task!r} built a {type(description).__name__}, not a TaskDescription")
    return description
