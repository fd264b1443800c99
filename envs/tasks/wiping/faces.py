"""The envs that serve the wiping task's ids (strings only: registering the ids imports no MuJoCo).

The episodic ids of every version are the generic face :class:`~rdmp_gym.envs.rhythmic_env.RhythmicTaskEnv` of the
task ``"wipe"`` (its hooks: :class:`~rdmp_gym.envs.tasks.wiping.task.WipingTask`). The step twins are the task's
own, on that face: :class:`~rdmp_gym.envs.tasks.wiping.step.WipeStepEnv` from v3 on and the v1/v2 step env
:class:`~rdmp_gym.envs.tasks.wiping.legacy_step.ArmarWipeStepEnv`; their observation (the canonical state, the
sponge's pose and velocity, the wrist force), their reward terms grown step by step and their end on a penetration
are the published step interface of the task, which the generic step twin's (the tool tip, a reward judged every
few steps) is not. v1 and v2 were published on ARMAR-III only."""

from __future__ import annotations

from typing import Any

__all__ = ["DEPRECATED", "EPISODIC", "LEGACY_STEP", "STEP", "faces"]

EPISODIC = "rdmp_gym.envs.rhythmic_env:RhythmicTaskEnv"
STEP = "rdmp_gym.envs.tasks.wiping.step:WipeStepEnv"
LEGACY_STEP = "rdmp_gym.envs.tasks.wiping.legacy_step:ArmarWipeStepEnv"
#: ``rdmp_gym/ArmarWipe-v0``: v1 without the cup, with a DeprecationWarning
DEPRECATED = "rdmp_gym.envs.tasks.wiping.env:deprecated_v0"
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
    step = (STEP if version >= 3 else LEGACY_STEP, {"version": version, **shift, **on_robot})
    return episodic, step
