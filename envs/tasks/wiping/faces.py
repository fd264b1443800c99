"""The envs that serve the wiping task's ids (strings only: registering the ids imports no MuJoCo).

The episodic ids of every version are the generic face :class:`~rdmp_gym.envs.rhythmic_env.RhythmicTaskEnv` of the
task ``"wipe"`` (its hooks: :class:`~rdmp_gym.envs.tasks.wiping.task.WipingTask`, and for the versions 1 and 2
:class:`~rdmp_gym.envs.tasks.wiping.legacy.task.LegacyWipingTask`). The step ids from v3 on are the
generic step twin :class:`~rdmp_gym.envs.rhythmic_step.RhythmicTaskStepEnv` of the task ``"wipe"``, with the task's
step book (:class:`~rdmp_gym.envs.tasks.wiping.step.WipeStepBook`: the canonical state, the sponge's pose and
velocity and the wrist force observed, every reward term grown step by step, the end on a penetration). The v1/v2
step ids are the v1/v2 step env :class:`~rdmp_gym.envs.tasks.wiping.legacy.step.ArmarWipeStepEnv`, which runs the
DMP online on that face; ``rdmp_gym/ArmarWipe-v0`` is :func:`~rdmp_gym.envs.tasks.wiping.legacy.env.deprecated_v0`.
v1 and v2 run on ARMAR-III only."""

from __future__ import annotations

from typing import Any

__all__ = ["DEPRECATED", "EPISODIC", "LEGACY_STEP", "STEP", "faces"]

EPISODIC = "rdmp_gym.envs.rhythmic_env:RhythmicTaskEnv"
STEP = "rdmp_gym.envs.rhythmic_step:RhythmicTaskStepEnv"
LEGACY_STEP = "rdmp_gym.envs.tasks.wiping.legacy.step:ArmarWipeStepEnv"
#: ``rdmp_gym/ArmarWipe-v0``: v1 without the cup, with a DeprecationWarning
DEPRECATED = "rdmp_gym.envs.tasks.wiping.legacy.env:deprecated_v0"
#: the step envs' path shift (m) per axis at a full action from v2 on: along the table, and in height
_STEP_SHIFT = (0.06, 0.06, 0.02)


def faces(robot: str, version: int) -> tuple[tuple[str, dict[str, Any]], tuple[str, dict[str, Any]]] | None:
    """``((episodic entry point, keywords), (step entry point, keywords))`` of the wiping task on ``robot`` (a
    registered robot name) at ``version``, or None where it has no ids."""
    if version < 3 and robot != "armar3":
        return None
    on_robot = {} if robot == "armar3" else {"robot": robot}
    episodic = (EPISODIC, {"task": "wipe", "obstacle": True, "version": version, **on_robot})
    shift = {} if version == 1 else {"max_shift": _STEP_SHIFT}
    if version >= 3:
        return episodic, (STEP, {"task": "wipe", "version": version, **shift, **on_robot})
    return episodic, (LEGACY_STEP, {"version": version, **shift, **on_robot})
