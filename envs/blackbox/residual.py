"""A step-based policy on top of the rhythmic DMP: each env step's action is a residual on the DMP's tracking command.

:class:`RhythmicResidualEnv` keeps the black-box wrapper's DMP (its transient from rest into the pattern, its tempo)
and its tracking controller, and lets a step-based learner (SAC, PPO) add to the controller's command what it
chooses from the body's state at that step. The observation is the env's own, followed by the DMP's desired joint
positions and velocities at the step (which tell the phase). At ``a = 0`` an episode is the wrapper's episode of its
DMP action bit for bit, so a learner starts from the rhythmic gait instead of from a random one::

    import gymnasium as gym
    import rdmp_gym.envs.blackbox  # noqa: F401  (registers the ids)

    env = gym.make("rdmp_gym/RhythmicResidual-v0", env_id="Swimmer-v5")    # the default pattern, residual 0.3
    observation, _ = env.reset(seed=0)
    observation, reward, terminated, truncated, info = env.step(env.action_space.sample())
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import gymnasium as gym
import numpy as np

from .wrapper import RhythmicBlackBoxWrapper, make_blackbox

__all__ = ["RESIDUAL_ID", "RhythmicResidualEnv", "make_residual"]

#: the id of :func:`make_residual` (``gym.make(RESIDUAL_ID, env_id="HalfCheetah-v5")``)
RESIDUAL_ID = "rdmp_gym/RhythmicResidual-v0"


class RhythmicResidualEnv(gym.Env):
    """The step env of a black-box wrapper's DMP with a residual command.

    Args:
        blackbox: the wrapper whose DMP, controller and step-based env are used (its feedback setting is ignored).
        dmp_action: ``[n]`` the wrapper's action that sets the DMP (default: zeros, the default pattern).
        scale: the residual's size: ``a = +-1`` adds ``+-scale`` times half the env's action range to the command.

    The env's command at step ``k`` is ``clip(controller(q_des[k + 1], qd_des[k + 1], q, qd) + scale * h * a)``,
    ``h = (high - low) / 2`` of the env's action space. Observation: ``[m + 2 d]`` the env's flattened observation,
    then the DMP's desired positions and velocities of the step to come. Reward, termination and ``info`` are the
    env's; the episode ends where the env's does (its time limit) or at the wrapper's last step.
    """

    def __init__(self, blackbox: RhythmicBlackBoxWrapper, dmp_action: np.ndarray | None = None,
                 scale: float = 0.3) -> None:
        if not isinstance(blackbox, RhythmicBlackBoxWrapper):
            raise TypeError(f"blackbox: expected a RhythmicBlackBoxWrapper, got {type(blackbox).__name__}")
        if not np.isfinite(scale) or scale < 0:
            raise ValueError(f"scale: expected a finite value >= 0, got {scale}")
        self.blackbox = blackbox
        n = blackbox.action_space.shape[0]
        action = np.zeros(n) if dmp_action is None else np.asarray(dmp_action, dtype=np.float64)
        if action.shape != (n,) or not np.all(np.isfinite(action)):
            raise ValueError(f"dmp_action: expected {n} finite values, got shape {action.shape}")
        self.theta = blackbox.param_map.to_params(np.clip(action, -1.0, 1.0))
        self.scale = float(scale)
        space = blackbox.env_action_space
        self._half_range = (space.high.astype(np.float64) - space.low.astype(np.float64)) / 2
        self.action_space = gym.spaces.Box(-1.0, 1.0, space.shape, np.float32)
        flat = gym.spaces.flatten_space(blackbox.env.observation_space)
        d = blackbox.n_joints
        self.observation_space = gym.spaces.Box(np.concatenate([flat.low, np.full(2 * d, -np.inf)]).astype(np.float32),
                                                np.concatenate([flat.high, np.full(2 * d, np.inf)]).astype(np.float32),
                                                dtype=np.float32)
        self.metadata = blackbox.metadata
        self.render_mode = blackbox.render_mode
        self._plan: tuple[np.ndarray, np.ndarray] | None = None
        self._state: tuple[np.ndarray, np.ndarray] | None = None
        self._step = 0

    def _observation(self, env_observation: Any) -> np.ndarray:
        """``[m + 2 d]`` the env's observation and the desired state of the step to come (the last one at the end)."""
        q_des, qd_des = self._plan
        k = min(self._step + 1, len(q_des) - 1)
        flat = self.blackbox._flatten(env_observation)
        return np.concatenate([flat, q_des[k], qd_des[k]]).astype(np.float32)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset the env (``seed``, ``options`` go to it) and plan the DMP's path from its joint state."""
        super().reset(seed=seed)
        observation, info = self.blackbox.env.reset(seed=seed, options=options)
        self._state = self.blackbox._joint_state()
        self._plan = self.blackbox.desired_trajectory(self.theta, *self._state)
        self._step = 0
        return self._observation(observation), info

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """One env step: the DMP's tracking command plus the residual ``action [n]`` (clipped to [-1, 1])."""
        if self._plan is None:
            raise RuntimeError("step: call reset() first")
        a = np.asarray(action, dtype=np.float64)
        if a.shape != self.action_space.shape or not np.all(np.isfinite(a)):
            raise ValueError(f"action: expected {self.action_space.shape} finite values, got shape {a.shape}")
        q_des, qd_des = self._plan
        k = self._step
        raw = np.asarray(self.blackbox.controller(q_des[k + 1], qd_des[k + 1], *self._state), dtype=np.float64)
        raw = raw + self.scale * self._half_range * np.clip(a, -1.0, 1.0)
        command = self.blackbox._clipped_command(raw).astype(self.blackbox.env_action_space.dtype)
        observation, reward, terminated, truncated, info = self.blackbox.env.step(command)
        self._state = self.blackbox._joint_state()
        self._step = k + 1
        truncated = bool(truncated) or (self._step >= self.blackbox.n_steps and not terminated)
        if terminated or truncated:
            finished = self._observation(observation)
            self._plan = None
            return finished, float(reward), bool(terminated), truncated, info
        return self._observation(observation), float(reward), bool(terminated), truncated, info

    def render(self) -> Any:
        return self.blackbox.render()

    def close(self) -> None:
        self.blackbox.close()
        super().close()


def make_residual(env_id: str, *, env_kwargs: Mapping[str, Any] | None = None, render_mode: str | None = None,
                  dmp_action: np.ndarray | None = None, scale: float = 0.3, **settings: Any) -> RhythmicResidualEnv:
    """:class:`RhythmicResidualEnv` on :func:`~rdmp_gym.envs.blackbox.wrapper.make_blackbox` ``(env_id, ...)`` with
    the wrapper's ``settings`` by name (its defaults for the env where none is given)."""
    return RhythmicResidualEnv(make_blackbox(env_id, env_kwargs=env_kwargs, render_mode=render_mode, **settings),
                               dmp_action, scale)
