"""The environment ids of rdmp-gym, defined once, and their registration with Gymnasium.

Every id is registered with a string entry point, so registering imports neither MuJoCo nor the env modules:
they load on the first ``gym.make``. ``import rdmp_gym.envs`` registers them (or ``gym.register_envs(rdmp_gym.envs)``,
Gymnasium's way of saying that an import is wanted for its side effect).
"""

from __future__ import annotations

import gymnasium as gym

__all__ = [
    "DEPRECATED_ENV_ID",
    "ENV_ID",
    "ENV_ID_V2",
    "ENV_ID_V3",
    "LATEST_ENV_ID",
    "LATEST_STEP_ID",
    "PANDA_ID_V3",
    "PANDA_STEP_ID_V3",
    "STEP_ID",
    "STEP_ID_V2",
    "STEP_ID_V3",
    "TRACKING_ID",
    "register_envs",
]

#: The wiping task's first version (the pattern loops in place at the patch centre).
ENV_ID = "rdmp_gym/ArmarWipe-v1"
#: The wiping pattern travels across the patch; every drawn context is solvable (:mod:`rdmp_gym.envs.versions`).
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

_WIPE = "rdmp_gym.envs.wipe_env:ArmarWipeEnv"
_STEP = "rdmp_gym.envs.step_env:ArmarWipeStepEnv"
_STEP_TWIN = "rdmp_gym.envs.step_twin:WipeStepEnv"

#: id -> (entry point, keywords)
_SPECS: dict[str, tuple[str, dict]] = {
    ENV_ID: (_WIPE, {"obstacle": True}),
    DEPRECATED_ENV_ID: ("rdmp_gym.envs.wipe_env:deprecated_v0", {}),
    TRACKING_ID: ("rdmp_gym.envs.tracking:TrackingEnv", {}),
    STEP_ID: (_STEP, {}),
    ENV_ID_V2: (_WIPE, {"obstacle": True, "version": 2}),
    STEP_ID_V2: (_STEP, {"version": 2, "max_shift": (0.06, 0.06, 0.02)}),
    ENV_ID_V3: (_WIPE, {"obstacle": True, "version": 3}),
    STEP_ID_V3: (_STEP_TWIN, {"version": 3, "max_shift": (0.06, 0.06, 0.02)}),
    PANDA_ID_V3: (_WIPE, {"obstacle": True, "version": 3, "robot": "panda"}),
    PANDA_STEP_ID_V3: (_STEP_TWIN, {"version": 3, "max_shift": (0.06, 0.06, 0.02), "robot": "panda"}),
}


def register_envs() -> None:
    """Register every rdmp-gym id with Gymnasium (ids already registered are left as they are)."""
    for env_id, (entry_point, kwargs) in _SPECS.items():
        if env_id not in gym.registry:
            gym.register(id=env_id, entry_point=entry_point, kwargs=kwargs)
