"""A MuJoCo-free episodic DMP task with the wiping env's contract: re-centre a wiping pattern.

The DMP is fitted to a wiping demonstration (a built-in style or the user's). The task is to follow the
same movement with its periodic pattern moved by a ``shift`` (the context: where the dirt is), blended
in over the transient, ``y*(t) = y_demo(t) + s(t / T) shift`` (``s`` a 7th-order smoothstep, ``T`` the
transient length), which the learner must produce through the DMP's weights and initial conditions.
One ``step`` is one whole rollout (``RhythmicDMP.rollout_batch``), sampled at ``control_rate``; the
per-step cost is the squared tracking error, ``c(t) = (|y(t) - y*(t)| / 1 cm)² dt / duration``, so the
return ``-sum_t c(t)`` is minus the mean squared error in cm². Actions ``a in [-1, 1]^n`` map to
``theta = theta_imitation + scales * a``.

Registered as ``rdmp_gym/DMPTracking-v0`` by ``rdmp_gym.envs``; the tests and quick CLI runs use it where
MuJoCo's physics is not needed.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np

from rdmp_gym import Demonstration, RhythmicDMP, wiping_demonstration
from rdmp_gym.dmp.fitting import FADE_BEFORE_T

from .contract import Metric, TaskContract

__all__ = ["TrackingEnv"]

_ERROR_UNIT = 0.01  # m


class TrackingEnv(gym.Env):
    """Track a shifted copy of a wiping demonstration with a rhythmic DMP (episodic, one step).

    Args:
        style: built-in demonstration style (1-4) that is fitted and shifted.
        demonstration: a user demonstration ``Y [L, 3]`` instead of ``style`` (at least ``duration`` long).
        n_periodic, n_transient: basis functions of the DMP.
        groups: the parameter groups the action refines.
        duration: rollout length (s).
        control_rate: cost samples per second (the length of ``cost_trace``).
        shift: ``[3]`` default displacement of the target pattern (m), used when ``context_range`` is 0.
        context_range: if > 0, every reset draws the x/y shift uniformly from ``±context_range`` m.
        weight_scale: action scale of a weight, as a fraction of its group's largest |weight|.
        phase_scale, radius_scale: action scales of ``phi0`` (rad) and of ``r0`` (fraction of ``r0``).

    ``step`` returns ``info`` with ``cost_trace`` (``[T]``), ``valid``, ``reward_terms`` and ``rms_error`` (the RMS
    distance to the target, m: the task's metric in its contract, :meth:`task_contract`; no ``is_success``).
    """

    metadata = {"render_modes": []}  # noqa: RUF012 (gymnasium's class attribute)

    def __init__(self, style: int = 1, demonstration: Demonstration | None = None, n_periodic: int = 15,
                 n_transient: int = 15,
                 groups: Sequence[str] = ("periodic", "transient", "initial"), duration: float = 6.0,
                 control_rate: float = 20.0, shift: Sequence[float] = (0.02, -0.015, 0.0),
                 context_range: float = 0.0, weight_scale: float = 0.5, phase_scale: float = 0.5,
                 radius_scale: float = 0.3) -> None:
        if duration <= 1.0 or control_rate <= 0.0:
            raise ValueError(f"duration/control_rate: expected > 1 s and > 0 Hz, got {duration}, {control_rate}")
        if context_range < 0.0 or context_range > 0.1:
            raise ValueError(f"context_range: expected a value in [0, 0.1] m, got {context_range}")
        if not 0.0 < radius_scale < 1.0:
            raise ValueError(f"radius_scale: expected a value in (0, 1), got {radius_scale}")
        self.demo = wiping_demonstration(style, rng=0) if demonstration is None else demonstration
        if self.demo.duration < duration or self.demo.n_dims != 3:
            raise ValueError(f"demonstration: expected 3 dimensions and at least {duration} s, "
                             f"got {self.demo.n_dims} and {self.demo.duration:.3g} s")
        self.dmp = RhythmicDMP.fit(self.demo, n_periodic, n_transient, **FADE_BEFORE_T)     # as published
        self.groups = tuple(groups)
        self.theta_imitation = self.dmp.get_params(self.groups)
        self.scales = self._scales(weight_scale, phase_scale, radius_scale)
        self.shift = np.asarray(shift, dtype=np.float64)
        if self.shift.shape != (3,):
            raise ValueError(f"shift: expected 3 values, got {self.shift.shape}")
        self.context_range = float(context_range)
        self.t = np.arange(round(duration * 100.0) + 1) / 100.0      # integration grid, 100 Hz
        stride = max(1, round(100.0 / control_rate))
        self._control = np.arange(0, self.t.size, stride)                   # [T_ctrl]
        self._dt = stride / 100.0
        n = self.theta_imitation.size
        self.action_space = gym.spaces.Box(-1.0, 1.0, (n,), np.float32)
        self.observation_space = gym.spaces.Box(-0.1, 0.1, (2,), np.float32)
        self._context = self.shift.copy()
        samples = self.demo.Y if self.demo.truth is None else self.demo.truth.clean
        elapsed = self.demo.t - self.demo.t[0]
        self._base = np.column_stack([np.interp(self.t, elapsed, column) for column in samples.T])   # [T, 3]
        u = np.clip(self.t / self.dmp.transients[0].length, 0.0, 1.0)
        self._blend = u**4 * (35.0 - 84.0 * u + 70.0 * u**2 - 20.0 * u**3)                         # [T]

    def _scales(self, weight_scale: float, phase_scale: float, radius_scale: float) -> np.ndarray:
        scales = np.empty_like(self.theta_imitation)
        for name, part in self.dmp.param_slices(self.groups).items():
            values = self.theta_imitation[part]
            if name.startswith("initial:"):
                scales[part] = (phase_scale, radius_scale * values[1])
            else:
                scales[part] = weight_scale * max(np.max(np.abs(values)), 1e-6)
        return scales

    def action_to_params(self, action: np.ndarray) -> np.ndarray:
        """``[n]`` action -> ``[P]`` DMP parameters of the selected groups."""
        return self.theta_imitation + self.scales * np.asarray(action, dtype=np.float64)

    def params_to_action(self, theta: np.ndarray) -> np.ndarray:
        """``[P]`` parameters -> ``[n]`` action (not clipped)."""
        return (np.asarray(theta, dtype=np.float64) - self.theta_imitation) / self.scales

    def action_time_weights(self) -> np.ndarray:
        """``[T_ctrl, n]`` activation in [0, 1] of each action dimension at each control step."""
        return self.dmp.param_time_weights(self.t[self._control], self.groups)

    def policy_dmp(self, theta: np.ndarray) -> RhythmicDMP:
        """The DMP with the parameters ``theta [P]`` of the selected groups."""
        return self.dmp.with_params(np.asarray(theta, dtype=np.float64), self.groups)

    def task_contract(self) -> TaskContract:
        """What the tools may know of the task: the tracking error per episode, the context's ``shift`` (x, y), no
        success; the executed path is the DMP's at the control steps."""
        return TaskContract(name="DMPTracking", metrics=(Metric("rms_error", "tracking error (m)",
                                                                higher_is_better=False, unit="m"),),
                            context_fields={"shift": (0, 2)}, has_success=False, smoothness="jerk",
                            dt=self._dt, path_labels=("x", "y", "z"))

    def executed_path(self, action: np.ndarray) -> np.ndarray:
        """``[T_ctrl, 3]`` the path :meth:`step` executes for ``action [n]`` (clipped to [-1, 1])."""
        return self.rollout_path(self.action_to_params(np.clip(self._checked(action), -1.0, 1.0)))

    def target(self) -> np.ndarray:
        """``[T, 3]`` the target path for the current context (on the integration grid)."""
        return self._base + self._blend[:, None] * self._context

    def rollout_path(self, theta: np.ndarray) -> np.ndarray:
        """``[T_ctrl, 3]`` the DMP's path with parameters ``theta [P]``, at the control steps."""
        return self.dmp.rollout_batch(np.asarray(theta, dtype=np.float64)[None], self.t, self.groups)[0][self._control]

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        unknown = set(options or {}) - {"shift"}
        if unknown:
            raise ValueError(f"options: unknown key(s) {sorted(unknown)}; expected 'shift'")
        if options and "shift" in options:
            self._context = np.asarray(options["shift"], dtype=np.float64)
        elif self.context_range > 0.0:
            xy = self.np_random.uniform(-self.context_range, self.context_range, 2)
            self._context = np.array([xy[0], xy[1], 0.0])
        else:
            self._context = self.shift.copy()
        return self._observation(), {}

    def _observation(self) -> np.ndarray:
        return np.clip(self._context[:2], -0.1, 0.1).astype(np.float32)

    def _checked(self, action: Any) -> np.ndarray:
        action = np.asarray(action, dtype=np.float64)
        if action.shape != self.action_space.shape or not np.all(np.isfinite(action)):
            raise ValueError(f"action: expected {self.action_space.shape} finite values, got shape {action.shape}")
        return action

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        theta = self.action_to_params(np.clip(self._checked(action), -1.0, 1.0))
        error = np.linalg.norm(self.rollout_path(theta) - self.target()[self._control], axis=1) / _ERROR_UNIT
        duration = float(self.t[-1])
        costs = error**2 * self._dt / duration
        reward = -float(costs.sum())
        info = {"cost_trace": costs, "valid": True, "reward_terms": {"tracking": reward},
                "rms_error": float(np.sqrt(np.mean(error**2))) * _ERROR_UNIT}
        return self._observation(), reward, True, False, info

