"""A rhythmic DMP policy on any step-based Gymnasium env with a continuous action space (black-box wrapper).

:class:`RhythmicBlackBoxWrapper` makes one ``step`` one whole episode: the action is the parameters of a rhythmic
DMP in the env's joint space, which a tracking controller follows on the env's own actions. See the docs' page "Your
own env". Importing this package registers ``rdmp_gym/RhythmicBlackBox-v0`` (:func:`make_blackbox`, keyword
``env_id``) and ``rdmp_gym/RhythmicResidual-v0`` (:func:`make_residual`: a step-based learner's residual on the DMP's
command, :mod:`~rdmp_gym.envs.blackbox.residual`)::

    import gymnasium as gym
    from rdmp_gym.envs.blackbox import RhythmicBlackBoxWrapper

    env = RhythmicBlackBoxWrapper(gym.make("Hopper-v5"))        # every setting derived from the MuJoCo model
    context, _ = env.reset(seed=0)
    context, episode_return, _, _, info = env.step(env.action_space.sample() * 0)   # the initial DMP

Settings are one :class:`BlackBoxSettings` (``RhythmicBlackBoxWrapper(env, settings, **overrides)``, e.g.
``p_gains=10.0, duration=4.0``).
"""

from __future__ import annotations

import gymnasium as gym

from .controller import CONTROLLERS, MujocoJoints, PDController, PositionController, VelocityController, make_controller
from .defaults import (
    BLACKBOX_SCALES,
    ENV_DEFAULTS,
    MODEL_RULES,
    ModelDefaults,
    default_demonstration,
    env_defaults,
    model_defaults,
)
from .params import JointParameterMap
from .residual import RESIDUAL_ID, RhythmicResidualEnv, make_residual
from .settings import DEFAULT_GROUPS, BlackBoxSettings
from .wrapper import WRAPPER_SETTINGS, RhythmicBlackBoxWrapper, make_blackbox, split_settings

__all__ = [
    "BLACKBOX_ID",
    "BLACKBOX_SCALES",
    "CONTROLLERS",
    "DEFAULT_GROUPS",
    "ENV_DEFAULTS",
    "MODEL_RULES",
    "RESIDUAL_ID",
    "WRAPPER_SETTINGS",
    "BlackBoxSettings",
    "JointParameterMap",
    "ModelDefaults",
    "MujocoJoints",
    "PDController",
    "PositionController",
    "RhythmicBlackBoxWrapper",
    "RhythmicResidualEnv",
    "VelocityController",
    "default_demonstration",
    "env_defaults",
    "make_blackbox",
    "make_controller",
    "make_residual",
    "model_defaults",
    "split_settings",
]

#: the id of :func:`make_blackbox` (``gym.make(BLACKBOX_ID, env_id="Swimmer-v5", ...)``)
BLACKBOX_ID = "rdmp_gym/RhythmicBlackBox-v0"

if BLACKBOX_ID not in gym.registry:
    gym.register(BLACKBOX_ID, entry_point="rdmp_gym.envs.blackbox.wrapper:make_blackbox")
if RESIDUAL_ID not in gym.registry:
    gym.register(RESIDUAL_ID, entry_point="rdmp_gym.envs.blackbox.residual:make_residual")
