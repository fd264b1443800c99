"""Gymnasium environments of rdmp-gym: table wiping with a rhythmic DMP on a simulated ARMAR-III.

Importing ``rdmp_gym`` (or this package) registers ``rdmp_gym/ArmarWipe-v2`` (and v1), an episodic env: one
``step`` runs one whole DMP rollout in MuJoCo (``terminated=True``; no ``max_episode_steps``)::

    import gymnasium as gym
    import rdmp_gym  # registers the env

    env = gym.make("rdmp_gym/ArmarWipe-v2")      # obstacle=True by default
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

import gymnasium as gym

from .clearance import CupClearance
from .context import CONTEXT_FIELDS, Context, ContextSpec
from .reward import TERMS, RewardWeights
from .scene import ARM_JOINTS, TablePose, WipeScene
from .tracking import TRACKING_ID, TrackingEnv
from .video import RecordEpisodeVideo
from .wipe_env import ArmarWipeEnv

__all__ = [
    "ARM_JOINTS",
    "CONTEXT_FIELDS",
    "DEPRECATED_ENV_ID",
    "ENV_ID",
    "ENV_ID_V2",
    "STEP_ID",
    "STEP_ID_V2",
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

ENV_ID = "rdmp_gym/ArmarWipe-v1"
#: Deprecated: v0's reward could be gamed (dirt off the table, touching counted as wiping, no self-collision).
#: It now makes the v1 env without the obstacle, with a DeprecationWarning, and will be removed.
DEPRECATED_ENV_ID = "rdmp_gym/ArmarWipe-v0"

if ENV_ID not in gym.registry:
    gym.register(id=ENV_ID, entry_point="rdmp_gym.envs.wipe_env:ArmarWipeEnv", kwargs={"obstacle": True})
if DEPRECATED_ENV_ID not in gym.registry:
    gym.register(id=DEPRECATED_ENV_ID, entry_point="rdmp_gym.envs.wipe_env:deprecated_v0")
if TRACKING_ID not in gym.registry:
    gym.register(id=TRACKING_ID, entry_point="rdmp_gym.envs.tracking:TrackingEnv")
STEP_ID = "rdmp_gym/ArmarWipeStep-v1"
if STEP_ID not in gym.registry:
    gym.register(id=STEP_ID, entry_point="rdmp_gym.envs.step_env:ArmarWipeStepEnv")
#: The pattern travels across the patch (``sweep_x``, ``sweep_y``), every drawn context is solvable, smoothness
#: does not charge a pattern for its size, and ``is_success`` needs an executable motion
#: (:mod:`rdmp_gym.envs.versions`).
ENV_ID_V2 = "rdmp_gym/ArmarWipe-v2"
STEP_ID_V2 = "rdmp_gym/ArmarWipeStep-v2"
if ENV_ID_V2 not in gym.registry:
    gym.register(id=ENV_ID_V2, entry_point="rdmp_gym.envs.wipe_env:ArmarWipeEnv", kwargs={"obstacle": True,
                                                                                       "version": 2})
if STEP_ID_V2 not in gym.registry:
    gym.register(id=STEP_ID_V2, entry_point="rdmp_gym.envs.step_env:ArmarWipeStepEnv",
                 kwargs={"version": 2, "max_shift": (0.06, 0.06, 0.02)})
