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

from rdmp_gym.validation import SettingTypeError

from .description import Outcome, Rejection, Solution, Stage, TaskDescription, TaskPlan, ToolPath

__all__ = ["BUILT_IN", "TASKS", "Outcome", "Rejection", "Solution", "Stage", "TaskDescription", "TaskEntry", "TaskPlan",
           "ToolPath", "get_task", "register_task"]


@dataclass(frozen=True)
class TaskEntry:
    """A registered task: ``id_name`` (its part of the env ids), ``versions`` and ``factory`` (a
    ``"module:attribute"`` string or a callable building the description from its settings).

    ``faces`` (a ``"module:attribute"`` string or a callable; default None: the rhythmic face and its step twin)
    names the envs that serve a task's ids where they are its own: ``faces(robot, version)`` gives
    ``((episodic entry point, keywords), (step entry point, keywords))``, or None where the task has no ids.
    ``cycle_versions`` (default None: the latest) are the versions with a cycle-level face.
    """

    id_name: str
    versions: tuple[int, ...]
    factory: Any
    faces: Any = None
    cycle_versions: tuple[int, ...] | None = None

    def has_cycle_face(self, version: int) -> bool:
        """Whether ``version`` has a cycle-level id (on the generic episodic face)."""
        return version in (self.cycle_versions or (max(self.versions),))

    def build(self, **settings: Any) -> TaskDescription:
        """The description with ``settings`` (a description class's :meth:`TaskDescription.build`)."""
        factory = self._factory()
        if isinstance(factory, type) and issubclass(factory, TaskDescription):
            return factory.build(**settings)
        return factory(**settings)

    def learner_defaults(self, version: int | None = None) -> dict[str, dict[str, Any]]:
        """The task's learner defaults (:meth:`~rdmp_gym.envs.tasks.description.TaskDescription.defaults_for`
        ``version``, its latest without one; empty where the factory is not a description class)."""
        factory = self._factory()
        if not (isinstance(factory, type) and issubclass(factory, TaskDescription)):
            return {}
        defaults = factory.defaults_for(max(self.versions) if version is None else version)
        return {agent: dict(options) for agent, options in defaults.items()}

    def face_settings(self, robot: Any, version: int) -> dict[str, Any]:
        """The settings a face adds when it builds the task for ``robot`` at ``version``
        (:meth:`~rdmp_gym.envs.tasks.description.TaskDescription.face_settings`; none where the factory is not a
        description class)."""
        factory = self._factory()
        if not (isinstance(factory, type) and issubclass(factory, TaskDescription)):
            return {}
        return factory.face_settings(robot, version)

    def typed_settings(self, settings: Any) -> Any:
        """The task's typed record of an env's settings
        (:meth:`~rdmp_gym.envs.tasks.description.TaskDescription.typed_settings`), or None."""
        factory = self._factory()
        if not (isinstance(factory, type) and issubclass(factory, TaskDescription)):
            return None
        return factory.typed_settings(settings)

    def face_specs(self, robot: str, version: int) -> tuple[tuple[str, dict], tuple[str, dict]] | None:
        """``((episodic entry point, keywords), (step entry point, keywords))`` of the task on ``robot`` at
        ``version``, or None where it has no ids there (the rhythmic face's for a task without ``faces``)."""
        if self.faces is None:
            return None
        return _load(self.faces)(robot, version)

    def _factory(self) -> Any:
        return _load(self.factory)


def _load(target: Any) -> Any:
    """``target`` itself, or the attribute a ``"module:attribute"`` string names."""
    if isinstance(target, str):
        module, attribute = target.split(":")
        return getattr(importlib.import_module(module), attribute)
    return target


#: name -> entry of every task on the rhythmic face
TASKS: dict[str, TaskEntry] = {
    "wipe": TaskEntry("Wipe", (1, 2, 3), "rdmp_gym.envs.tasks.wiping.task:WipingTask",
                      faces="rdmp_gym.envs.tasks.wiping.faces:faces"),
    "drum": TaskEntry("Drum", (1, 2), "rdmp_gym.envs.tasks.drumming:DrumTask", cycle_versions=(1, 2)),
}
#: the names of the tasks this package brings, which :func:`register_task` replaces only when told to
BUILT_IN = frozenset(TASKS)


def register_task(name: str, factory: Any, id_name: str | None = None, versions: tuple[int, ...] = (1,),
                  faces: Any = None, *, replace: bool = False) -> None:
    """Make a task available by ``name``; ``factory(**settings)`` builds its description (a class, a callable or a
    ``"module:attribute"`` string); ``faces``: see :class:`TaskEntry`.

    Registering a name again with the same entry changes nothing; a different entry for a registered name (a built-in
    task's, :data:`BUILT_IN`, or one registered before) is a ValueError unless ``replace`` is True: the env ids
    registered for a name build whatever task the name holds when they are made.
    """
    if not isinstance(name, str) or not name:
        raise SettingTypeError(f"name: expected a task name (a non-empty str), got {name!r}")
    if not (callable(factory) or isinstance(factory, str)):
        raise TypeError(f"factory: expected a TaskDescription class, a callable or 'module:attribute', got "
                        f"{type(factory).__name__}")
    if id_name is not None and (not isinstance(id_name, str) or not id_name.isidentifier()):
        raise ValueError(f"id_name: expected the task's part of its env ids (letters and digits), got {id_name!r}")
    if not isinstance(versions, (tuple, list)) or not versions \
            or not all(isinstance(v, int) and not isinstance(v, bool) and v >= 1 for v in versions):
        raise ValueError(f"versions: expected one or more integers >= 1, got {versions!r}")
    entry = TaskEntry(id_name or name.capitalize(), tuple(versions), factory, faces)
    current = TASKS.get(name)
    if current is not None and current != entry and not replace:
        kind = "a built-in task" if name in BUILT_IN else "a registered task"
        raise ValueError(f"name: {name!r} is {kind} ({current.factory!r}); pass replace=True to replace it (the env "
                         f"ids registered for {name!r} then build the new task) or choose another name")
    TASKS[name] = entry


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
