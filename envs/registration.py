"""The environment ids of rdmp-gym, defined once, and their registration with Gymnasium.

Every id is registered with a string entry point, so registering imports neither MuJoCo nor the env modules:
they load on the first ``gym.make``. ``import rdmp_gym.envs`` registers them (or ``gym.register_envs(rdmp_gym.envs)``,
Gymnasium's way of saying that an import is wanted for its side effect).
"""

from __future__ import annotations

import copy
import inspect
from collections.abc import Mapping
from typing import Any

import gymnasium as gym

from .specs import find_spec, is_episodic
from .tasks import TASKS

__all__ = [
    "DEPRECATED_ENV_ID",
    "ENV_ID",
    "ENV_ID_V2",
    "ENV_ID_V3",
    "LATEST_ENV_ID",
    "LATEST_STEP_ID",
    "PANDA_ID_V3",
    "PANDA_STEP_ID_V3",
    "ROBOT_ID_NAMES",
    "STEP_ID",
    "STEP_ID_V2",
    "STEP_ID_V3",
    "TRACKING_ID",
    "cycle_id",
    "env_settings",
    "learner_defaults",
    "register_envs",
    "register_task_ids",
    "task_ids",
]

#: The wiping task's first version (the pattern loops in place at the patch centre).
ENV_ID = "rdmp_gym/ArmarWipe-v1"
#: The wiping pattern travels across the patch; every drawn context is solvable
#: (:mod:`rdmp_gym.envs.tasks.wiping.versions`).
ENV_ID_V2 = "rdmp_gym/ArmarWipe-v2"
#: Step-based twins (one control step per ``step``) of v1 and v2.
STEP_ID = "rdmp_gym/ArmarWipeStep-v1"
STEP_ID_V2 = "rdmp_gym/ArmarWipeStep-v2"
#: The task on a composed scene with a smooth-path success, for each robot, and their step twins.
ENV_ID_V3 = "rdmp_gym/ArmarWipe-v3"
STEP_ID_V3 = "rdmp_gym/ArmarWipeStep-v3"
PANDA_ID_V3 = "rdmp_gym/PandaWipe-v3"
PANDA_STEP_ID_V3 = "rdmp_gym/PandaWipeStep-v3"
#: The current wiping task and its step twin: what commands use when no ``--env`` is given.
LATEST_ENV_ID = ENV_ID_V3
LATEST_STEP_ID = STEP_ID_V3
#: Deprecated: v0's reward could be gamed; it makes the v1 env without the obstacle, with a DeprecationWarning.
DEPRECATED_ENV_ID = "rdmp_gym/ArmarWipe-v0"
#: Tracking a target rhythm with the DMP (no MuJoCo).
TRACKING_ID = "rdmp_gym/DMPTracking-v0"

#: robot registry name -> its part of an env id (``rdmp_gym/{Robot}{Task}-v{N}``)
ROBOT_ID_NAMES: dict[str, str] = {"armar3": "Armar", "panda": "Panda"}

_RHYTHMIC = "rdmp_gym.envs.rhythmic_env:RhythmicTaskEnv"
_RHYTHMIC_STEP = "rdmp_gym.envs.rhythmic_step:RhythmicTaskStepEnv"
_RHYTHMIC_CYCLE = "rdmp_gym.envs.cycle_env:RhythmicCycleEnv"

#: ids beside the tasks' (the tasks' ids come from :data:`rdmp_gym.envs.tasks.TASKS`): id -> (entry point, keywords)
_SPECS: dict[str, tuple[str, dict]] = {
    DEPRECATED_ENV_ID: ("rdmp_gym.envs.tasks.wiping.legacy.env:deprecated_v0", {}),
    TRACKING_ID: ("rdmp_gym.envs.tracking:TrackingEnv", {}),
}
#: ids beside the tasks' whose keywords are a task's settings: id -> the task
#: (:meth:`~rdmp_gym.envs.tasks.TaskEntry.typed_settings`)
_SPECS_TASK: dict[str, str] = {DEPRECATED_ENV_ID: "wipe"}


def learner_defaults(env_id: str) -> dict[str, dict[str, Any]]:
    """What a learner may read from the task of a registered episodic env: ``{agent: options}`` (a fresh copy; empty
    for ids of other packages, step twins and tasks that set none). Learners never name a task; they read this."""
    if env_id not in gym.registry:
        return {}
    spec = gym.registry[env_id]
    kwargs = spec.kwargs or {}
    defaults: Mapping[str, Any] = {}
    if spec.entry_point == _RHYTHMIC and kwargs.get("task") in TASKS:
        defaults = TASKS[kwargs["task"]].learner_defaults(kwargs.get("version"))
    else:
        for task, entry in TASKS.items():               # a task on its own faces: its episodic ids
            for robot in ROBOT_ID_NAMES:
                for version in entry.versions:
                    if entry.faces is not None and task_ids(task, robot, version)[0] == env_id:
                        defaults = entry.learner_defaults(version)
    return copy.deepcopy(dict(defaults))


def env_settings(env_id: str, kwargs: Mapping[str, Any] | None = None) -> Any:
    """The settings ``gym.make(env_id, **kwargs)`` builds its env with, validated without building it.

    The episodic ids of a task with a typed record of its settings give it
    (:meth:`~rdmp_gym.envs.tasks.description.TaskDescription.typed_settings`: the wiping task's
    :class:`~rdmp_gym.envs.tasks.wiping.settings.EnvConfig`, also for the deprecated v0); the other ids of this package
    give the keywords (registered and given), checked against the env's signature and, for a task of the rhythmic
    face or its step twin, the face's keywords as the face's episodic ids check them; ids of other packages give the
    keywords as they are (string or class entry point alike): for an episodic env
    (:func:`~rdmp_gym.envs.specs.is_episodic`) checked against its signature, for a step-based env checked to be
    keywords of the env or settings of the rhythmic black-box wrapper that runs it
    (:func:`~rdmp_gym.envs.blackbox.split_settings`). Raises ValueError for an unknown id, and TypeError or ValueError
    naming a setting the env does not take or a value it refuses.
    """
    spec = find_spec(env_id)
    settings = {**(spec.kwargs or {}), **dict(kwargs or {})}
    if not isinstance(spec.entry_point, str) or not spec.entry_point.startswith("rdmp_gym."):
        if not is_episodic(env_id):             # a step-based env: its keywords, or the black-box wrapper's
            from .blackbox.wrapper import split_settings

            split_settings(env_id, kwargs)
        else:
            _bound(env_id, spec.entry_point, settings)
        return settings
    if env_id in _SPECS_TASK:
        return TASKS[_SPECS_TASK[env_id]].typed_settings(settings)
    if spec.entry_point == _RHYTHMIC:
        return _face_settings(env_id, settings)
    bound = _bound(env_id, spec.entry_point, settings)
    if spec.entry_point == _RHYTHMIC_STEP:
        _face_settings(env_id, bound.arguments.get("kwargs", {}))
    return settings


def _face_settings(env_id: str, settings: dict[str, Any]) -> Any:
    """The episodic face's keywords ``settings`` as the task's typed record where it has one, else as they are,
    checked against the face's signature and the task's description."""
    if settings.get("task") in TASKS:
        typed = TASKS[settings["task"]].typed_settings({k: v for k, v in settings.items() if k != "task"})
        if typed is not None:
            return typed
    bound = _bound(env_id, _RHYTHMIC, settings)
    from .tasks import get_task

    try:
        get_task(settings["task"], **bound.arguments.get("task_settings", {}))
    except TypeError as error:
        raise TypeError(f"env_kwargs: {env_id} does not take these settings: {error}") from None
    return settings


def _bound(env_id: str, entry_point: Any, settings: dict[str, Any]) -> inspect.BoundArguments:
    """``settings`` bound to the signature of the env at ``entry_point`` (a ``"module:name"`` string, a class or a
    function; TypeError naming ``env_id`` if they do not fit)."""
    creator = gym.envs.registration.load_env_creator(entry_point) if isinstance(entry_point, str) else entry_point
    try:
        return inspect.signature(creator).bind(**settings)
    except TypeError as error:
        raise TypeError(f"env_kwargs: {env_id} does not take these settings: {error}") from None


def task_ids(task: str, robot: str, version: int) -> tuple[str, str]:
    """The episodic and the step id of a task of the rhythmic face on a robot, e.g. ``("rdmp_gym/ArmarDrum-v1",
    "rdmp_gym/ArmarDrumStep-v1")`` for ``("drum", "armar3", 1)``."""
    name = f"{ROBOT_ID_NAMES.get(robot, robot.capitalize())}{TASKS[task].id_name}"
    return f"rdmp_gym/{name}-v{version}", f"rdmp_gym/{name}Step-v{version}"


def cycle_id(episodic_id: str) -> str:
    """The cycle-level face's id of an episodic id of the rhythmic face (:mod:`rdmp_gym.envs.cycle_env`), e.g.
    ``"rdmp_gym/ArmarDrumCycle-v1"`` for ``"rdmp_gym/ArmarDrum-v1"``; a task's current version has one, and so do
    the versions its entry names (``TaskEntry.cycle_versions``)."""
    head, _, version = episodic_id.rpartition("-v")
    return f"{head}Cycle-v{version}"


def register_task_ids(task: str, robots: tuple[str, ...] = tuple(ROBOT_ID_NAMES)) -> list[str]:
    """Register the ids of ``task`` (a name in :data:`rdmp_gym.envs.tasks.TASKS`) on ``robots`` (registered robot
    names, :data:`rdmp_gym.envs.robots.ROBOTS`) for each of its versions; returns the episodic ids. A task or robot
    that is not registered is a ValueError naming it and the registered ones."""
    if not isinstance(task, str) or task not in TASKS:
        raise ValueError(f"task: expected a registered task, one of {sorted(TASKS)} (register one with "
                         f"rdmp_gym.envs.tasks.register_task first), got {task!r}")
    from .robots import ROBOTS

    if not isinstance(robots, (tuple, list)) or not all(isinstance(robot, str) and robot in ROBOTS for robot in robots):
        raise ValueError(f"robots: expected a tuple of registered robot names, some of {sorted(ROBOTS)}, got "
                         f"{robots!r}")
    ids = []
    entry = TASKS[task]
    for robot in robots:
        for version in entry.versions:
            episodic, step = task_ids(task, robot, version)
            kwargs = {"task": task, "robot": robot, "version": version}
            faces = ((_RHYTHMIC, kwargs), (_RHYTHMIC_STEP, kwargs)) if entry.faces is None else entry.face_specs(
                robot, version)
            if faces is None:                             # the task has no ids on this robot at this version
                continue
            for env_id, (entry_point, face_kwargs) in zip((episodic, step), faces, strict=True):
                if env_id not in gym.registry:
                    gym.register(id=env_id, entry_point=entry_point, kwargs=face_kwargs)
            if entry.has_cycle_face(version) and faces[0][0] == _RHYTHMIC and cycle_id(episodic) not in gym.registry:
                gym.register(id=cycle_id(episodic), entry_point=_RHYTHMIC_CYCLE, kwargs=faces[0][1])
            ids.append(episodic)
    return ids


def register_envs() -> None:
    """Register every rdmp-gym id with Gymnasium (ids already registered are left as they are): every task's on every
    robot (:data:`rdmp_gym.envs.tasks.TASKS`), the deprecated wiping v0 and the tracking env."""
    for task in TASKS:
        register_task_ids(task)
    for env_id, (entry_point, kwargs) in _SPECS.items():
        if env_id not in gym.registry:
            gym.register(id=env_id, entry_point=entry_point, kwargs=kwargs)
