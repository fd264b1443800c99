"""Gymnasium environments of rdmp-gym: rhythmic tasks with a rhythmic DMP, on ARMAR-III or a Franka Panda.

Importing this package registers the ids (:mod:`rdmp_gym.envs.registration`, string entry points) of the tasks of
:mod:`rdmp_gym.envs.tasks`, every episodic id on the face :class:`~rdmp_gym.envs.rhythmic_env.RhythmicTaskEnv`:
table wiping (:mod:`rdmp_gym.envs.tasks.wiping`), the current ``rdmp_gym/ArmarWipe-v3`` and ``rdmp_gym/PandaWipe-v3``
and their step twins (the task's own), the published ``-v2`` and ``-v1``; drumming to a changing beat,
``rdmp_gym/ArmarDrum-v1`` and ``rdmp_gym/PandaDrum-v1`` and their step twins.
An episodic env's ``step`` runs one whole DMP rollout in MuJoCo (``terminated=True``)::

    import gymnasium as gym
    import rdmp_gym.envs  # registers the envs

    env = gym.make("rdmp_gym/ArmarWipe-v3")
    obs, info = env.reset(seed=0)
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample() * 0)  # the imitation

Rendering is offscreen (``render_mode="rgb_array"``). MuJoCo picks its OpenGL backend when it is
first imported; on a machine without a display, importing this package sets ``MUJOCO_GL=egl``
(which needs no GPU: Mesa's llvmpipe renders) unless ``MUJOCO_GL`` is already set.
"""

from __future__ import annotations

import os

if "MUJOCO_GL" not in os.environ and not os.environ.get("DISPLAY"):
    os.environ["MUJOCO_GL"] = "egl"

from .registration import (
    DEPRECATED_ENV_ID,
    ENV_ID,
    ENV_ID_V2,
    ENV_ID_V3,
    LATEST_ENV_ID,
    LATEST_STEP_ID,
    PANDA_ID_V3,
    PANDA_STEP_ID_V3,
    STEP_ID,
    STEP_ID_V2,
    STEP_ID_V3,
    TRACKING_ID,
    register_envs,
)
from .tasks.wiping.clearance import CupClearance
from .tasks.wiping.context import CONTEXT_FIELDS, Context, ContextSpec
from .tasks.wiping.env import ArmarWipeEnv
from .tasks.wiping.legacy.scene import WipeScene
from .tasks.wiping.reward import TERMS, RewardWeights
from .tasks.wiping.scene import TablePose
from .tracking import TrackingEnv
from .video import RecordEpisodeVideo

__all__ = [
    "CONTEXT_FIELDS",
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
    "TERMS",
    "TRACKING_ID",
    "ArmarWipeEnv",
    "Context",
    "ContextSpec",
    "CupClearance",
    "RecordEpisodeVideo",
    "RewardWeights",
    "TablePose",
    "TrackingEnv",
    "WipeScene",
]

register_envs()
