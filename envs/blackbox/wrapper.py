"""A rhythmic DMP policy on any step-based Gymnasium env: one ``step`` = one whole episode (black box).

:class:`RhythmicBlackBoxWrapper` turns an env with a continuous ``Box`` action space into an episodic env whose
action ``a in [-1, 1]^n`` is the parameters of a rhythmic DMP (Ernesti et al. 2012) in the env's joint space,
``theta = theta0 + scale * a`` (:class:`~rdmp_gym.envs.blackbox.params.JointParameterMap`; ``a = 0`` is the initial
DMP: fitted to a demonstration, else to a small sine per joint, :mod:`rdmp_gym.envs.blackbox.defaults`).

One ``step(a)``:

1. rolls the DMP out over ``duration`` on the env's step grid, from the joint state the env was reset to (the
   transient carries it into the rhythm; nothing is teleported): desired positions and velocities ``[T + 1, d]``;
2. runs the env step by step: a tracking controller (:mod:`rdmp_gym.envs.blackbox.controller`) maps the joint state
   and the desired state at the end of the step to the env's action, clipped to its box;
3. stops early where the env says ``terminated`` or ``truncated``, and returns the summed reward, the context
   (the reset observation under ``context_mask``) and ``info`` (the executed and desired trajectories, the tracking
   error, ``env_steps``, the per-step rewards and ``cost_trace``, the per-step cost zero-padded to ``T``).

With the setting ``feedback="linear"`` the policy reacts to the body: the controller's command gains ``K z``, the
env's observation ``z`` standardised on the ``a = 0`` gait (:class:`~rdmp_gym.envs.blackbox.controller.LinearFeedback`)
and the gains ``K`` the action's last group ``feedback`` (zero at ``a = 0``, which stays the open-loop gait).

The settings are one :class:`~rdmp_gym.envs.blackbox.settings.BlackBoxSettings`; on a MuJoCo env every setting has a
default derived from the model (:func:`~rdmp_gym.envs.blackbox.defaults.model_defaults`). The wrapper declares its
task contract (:meth:`RhythmicBlackBoxWrapper.task_contract`, :meth:`~RhythmicBlackBoxWrapper.executed_path`) and
records videos (:meth:`~RhythmicBlackBoxWrapper.record_episode`, where :meth:`~RhythmicBlackBoxWrapper.can_record`).

The names follow fancy_gym's ``BlackBoxWrapper`` where they fit (``duration``, ``context_mask``, a tracking
controller with ``p_gains``/``d_gains``). It is a :class:`gymnasium.Env` that holds the step-based env as
``.env`` rather than a ``gymnasium.Wrapper``: the learners of :mod:`rdmp_gym.agents` find the episodic methods
(``action_to_params``, ``params_to_action``, ``action_time_weights``) on ``env.unwrapped``, which is this object.
"""

from __future__ import annotations

import copy
import inspect
from collections.abc import Callable, Mapping
from dataclasses import replace
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from rdmp_gym import RhythmicDMP

from ..action import checked_action
from ..contract import Metric, TaskContract
from ..specs import find_spec
from .controller import JointReader, LinearFeedback, MujocoJoints, TrackingController, check_gains, make_controller
from .defaults import ModelDefaults, default_demonstration, env_defaults, model_defaults
from .params import JointParameterMap
from .settings import DEFAULT_GROUPS, BlackBoxSettings

__all__ = ["DEFAULT_GROUPS", "WRAPPER_SETTINGS", "RhythmicBlackBoxWrapper", "make_blackbox", "split_settings"]

#: the most frames per second of :meth:`RhythmicBlackBoxWrapper.record_episode` (it keeps every k-th env step)
VIDEO_FPS = 30.0
#: the reset seed of the ``a = 0`` episode whose observations standardise the feedback's features
FEEDBACK_REFERENCE_SEED = 0


class RhythmicBlackBoxWrapper(gym.Env):
    """Episodic black-box env: a rhythmic joint-space DMP tracked on a step-based env for one whole episode.

    Args:
        env: a step-based Gymnasium env with a continuous ``Box`` action space (e.g. ``gym.make("Swimmer-v5")``),
            or one that only looks like one (``reset``, ``step``, a ``Box`` action space; no ``spec`` or
            ``metadata`` needed: then give ``duration`` and, without a MuJoCo model, ``joint_state`` and ``dt``).
        settings: a :class:`~rdmp_gym.envs.blackbox.settings.BlackBoxSettings` (default: all defaults).
        **overrides: settings by name, replacing those of ``settings`` (``p_gains=5.0``, ``duration=4.0``, ...).

    A setting left None is taken from :data:`~rdmp_gym.envs.blackbox.defaults.ENV_DEFAULTS` for a known env
    (Swimmer, HalfCheetah), else from the MuJoCo model (:func:`~rdmp_gym.envs.blackbox.defaults.model_defaults`:
    the controller, the PD gains, the posture and the default pattern), else from the generic fallbacks named in
    :class:`~rdmp_gym.envs.blackbox.settings.BlackBoxSettings`.

    Attributes:
        settings: the settings as given. model_defaults: what the MuJoCo model suggests (None without one).
        has_success: whether the env reports ``info["is_success"]`` (told by one env step when it is built).
        feedback: the :class:`~rdmp_gym.envs.blackbox.controller.LinearFeedback` (its statistics from one ``a = 0``
            episode at reset seed :data:`FEEDBACK_REFERENCE_SEED`, run when the wrapper is built), None in open loop.

    Raises:
        ValueError: naming the argument, for an env it cannot drive (a discrete action space, no joint state to
            track, no step length or time limit) and for inconsistent settings; TypeError for an unknown setting.
    """

    def __init__(self, env: gym.Env, settings: BlackBoxSettings | None = None, **overrides: Any) -> None:
        self.settings = BlackBoxSettings.build(settings, **overrides)
        if not isinstance(env, gym.Env):
            raise TypeError(f"env: expected a gymnasium.Env, got {type(env).__name__}")
        space = env.action_space
        if not isinstance(space, gym.spaces.Box) or len(space.shape) != 1 \
                or not np.issubdtype(space.dtype, np.floating):
            raise ValueError(f"env: the rhythmic black-box wrapper needs a continuous Box action space (one float per "
                             f"actuator), got {space}")
        self.env = env
        self.env_action_space = space
        spec = getattr(env, "spec", None)
        #: the env's name: its id, or its class's name where it has no spec
        self.env_name = spec.id if spec is not None else type(env.unwrapped).__name__
        chosen = {**(env_defaults(spec.id) if spec is not None else {}), **self._given()}
        self.dt = self._step_length(env, self.settings.dt)
        self.n_steps = self._steps(env, self.settings.duration)
        #: ``[T + 1]`` the env step grid (s): the reset state at 0, the end of env step k at ``t[k + 1]``
        self.t = np.arange(self.n_steps + 1) * self.dt
        self._read, joints = self._reader(env, self.settings.joint_state)
        self.model_defaults = None if joints is None else model_defaults(env, joints, self.dt)
        self.posture = self._posture(env, chosen.get("posture"), joints)
        self.n_joints = int(self.posture.size)
        #: the joints' names (the executed path's columns)
        self.joint_names = joints.names if joints is not None else tuple(f"joint {j}" for j in range(self.n_joints))
        self.controller = self._controller(chosen, int(space.shape[0]))
        self.dmp = self._initial_dmp(chosen)
        self.groups = self.settings.groups
        self._flat_space = gym.spaces.flatten_space(env.observation_space)
        self.param_map = JointParameterMap(self.dmp, self.groups, self.settings.scales, self._cycle_motion(),
                                           self._feedback_units())
        self.theta0 = self.param_map.theta0.copy()
        self.action_space = gym.spaces.Box(-1.0, 1.0, (self.param_map.size,), np.float32)
        self.context_mask = self._mask(self.settings.context_mask)
        self.observation_space = gym.spaces.Box(self._flat_space.low[self.context_mask].astype(np.float32),
                                                self._flat_space.high[self.context_mask].astype(np.float32),
                                                dtype=np.float32)
        self.metadata = dict(getattr(env, "metadata", None) or {})
        self.render_mode = getattr(env, "render_mode", None)
        self.has_success = self._reports_success()
        self._start: tuple[np.ndarray, np.ndarray] | None = None
        self._context = np.zeros(int(self.context_mask.sum()), dtype=np.float32)
        self._frames: list[np.ndarray] | None = None
        self._frame_stride = 1
        self._reset_observation: np.ndarray | None = None
        self.feedback: LinearFeedback | None = None
        if self.settings.feedback is not None:
            self.feedback = self._reference_feedback()

    # ------------------------------------------------------------------ construction
    def _given(self) -> dict[str, Any]:
        """The settings given (not None) among those :data:`ENV_DEFAULTS` and the model may fill in."""
        names = ("controller", "p_gains", "d_gains", "period", "amplitude", "phases", "start_periods", "posture")
        return {name: getattr(self.settings, name) for name in names if getattr(self.settings, name) is not None}

    @staticmethod
    def _step_length(env: gym.Env, dt: float | None) -> float:
        value = getattr(env.unwrapped, "dt", None) if dt is None else dt
        if value is None:
            raise ValueError("dt: the env has no `dt` (seconds per env step); pass dt=...")
        value = float(value)
        if not (np.isfinite(value) and value > 0.0):
            raise ValueError(f"dt: expected seconds per env step > 0, got {value!r}")
        return value

    @staticmethod
    def time_limit(env: gym.Env) -> int | None:
        """The env's time limit in env steps: the smallest of its ``spec.max_episode_steps`` and of the
        ``gymnasium.wrappers.TimeLimit`` wrappers around it; None where it has neither."""
        limits = []
        spec_limit = getattr(getattr(env, "spec", None), "max_episode_steps", None)
        if spec_limit is not None:
            limits.append(int(spec_limit))
        layer = env
        while isinstance(layer, gym.Wrapper):
            if isinstance(layer, gym.wrappers.TimeLimit):
                limits.append(int(layer._max_episode_steps))
            layer = layer.env
        return min(limits) if limits else None

    def _steps(self, env: gym.Env, duration: float | None) -> int:
        limit = self.time_limit(env)
        if duration is None:
            if limit is None:
                raise ValueError("duration: the env has no time limit (no spec.max_episode_steps, no TimeLimit "
                                 "wrapper) to take the episode's length from; pass duration=... (s, a whole number of "
                                 f"env steps of {self.dt:g} s)")
            return int(limit)
        steps = round(duration / self.dt)
        if steps < 1 or abs(steps * self.dt - duration) > 1e-6 * max(duration, 1.0):
            raise ValueError(f"duration: expected a whole number (>= 1) of env steps of {self.dt:g} s, "
                             f"got {duration!r}")
        if limit is not None and steps > limit:
            raise ValueError(f"duration: {duration:g} s is {steps} env steps, more than the env's time limit of "
                             f"{limit} steps ({limit * self.dt:g} s), which would cut every episode short; pass "
                             f"duration <= {limit * self.dt:g} or raise the env's limit")
        return int(steps)

    @staticmethod
    def _reader(env: gym.Env, joint_state: JointReader | None) -> tuple[Callable, MujocoJoints | None]:
        if joint_state is not None:
            return joint_state, None
        if not MujocoJoints.available(env):
            raise ValueError("joint_state: the env has no MuJoCo model and data (env.unwrapped.model/.data) to read "
                             "the actuated joints from, so there is no joint state to track; pass "
                             "joint_state=callable(env) -> (q [d], qd [d])")
        joints = MujocoJoints(env)
        return joints, joints

    def _posture(self, env: gym.Env, posture: Any, joints: MujocoJoints | None) -> np.ndarray:
        if posture is None and self.model_defaults is not None:
            posture = self.model_defaults.posture
        if posture is None:
            env.reset(seed=0)
            posture = self._joint_state()[0]
        values = np.asarray(posture, dtype=np.float64)
        if values.ndim != 1 or values.size == 0 or not np.all(np.isfinite(values)):
            raise ValueError(f"posture: expected [d] finite joint positions, got {posture!r}")
        if joints is not None and values.size != joints.qpos_adr.size:
            raise ValueError(f"posture: expected {joints.qpos_adr.size} joint positions (one per actuator), "
                             f"got {values.size}")
        return values.copy()

    def _controller(self, chosen: Mapping[str, Any], n_actions: int) -> TrackingController:
        """The tracking controller: given, else the known env's, else the model's (with its gains), else "pd"."""
        derived: ModelDefaults | None = self.model_defaults
        controller = chosen.get("controller")
        if controller is None and derived is not None:
            if derived.controller is None:
                raise ValueError(f"controller: {derived.no_controller}")
            controller = derived.controller
        controller = "pd" if controller is None else controller
        p_gains, d_gains = chosen.get("p_gains"), chosen.get("d_gains")
        if controller == "pd" and derived is not None and derived.controller == "pd":
            if p_gains is None:
                p_gains = derived.p_gains
            if d_gains is None:
                d_gains = derived.critical_damping(check_gains(p_gains, self.n_joints, "p_gains"))
        return make_controller(controller, self.n_joints, n_actions, p_gains, d_gains)

    def _initial_dmp(self, chosen: Mapping[str, Any]) -> RhythmicDMP:
        settings, derived = self.settings, self.model_defaults
        if settings.dmp is not None:
            if settings.dmp.n_dims != self.n_joints:
                raise ValueError(f"dmp: has {settings.dmp.n_dims} dimensions, the env has {self.n_joints} joints")
            return settings.dmp
        keywords = dict(settings.fit_kwargs)
        if settings.demonstration is not None:
            if settings.demonstration.n_dims != self.n_joints:
                raise ValueError(f"demonstration: has {settings.demonstration.n_dims} dimensions, the env has "
                                 f"{self.n_joints} joints (one DMP dimension per actuated joint)")
            return RhythmicDMP.fit(settings.demonstration, settings.n_periodic, settings.n_transient, **keywords)
        period = chosen.get("period", derived.period if derived is not None else 1.0)
        amplitude = chosen.get("amplitude", derived.amplitude if derived is not None else 0.2)
        demo, segmentation = default_demonstration(self.posture, period, amplitude, chosen.get("phases"),
                                                   start=chosen.get("start_periods", 1.0))
        keywords.setdefault("segmentations", [segmentation])
        keywords.setdefault("period", segmentation.period)
        return RhythmicDMP.fit(demo, settings.n_periodic, settings.n_transient, **keywords)

    def _cycle_motion(self) -> np.ndarray:
        """``[d]`` each joint's peak-to-peak motion over the initial DMP's first cycle after the transient."""
        start = self.dmp.transients[0].length
        t = np.linspace(0.0, start + self.dmp.period, 400)
        path = self.dmp.rollout(t)[t >= start]
        return np.ptp(path, axis=0)

    def _mask(self, context_mask: tuple[bool, ...] | None) -> np.ndarray:
        size = int(self._flat_space.shape[0])
        if context_mask is None:
            return np.ones(size, dtype=bool)
        mask = np.asarray(context_mask, dtype=bool)
        if mask.shape != (size,):
            raise ValueError(f"context_mask: expected {size} booleans (one per entry of the env's flattened "
                             f"observation), got {mask.size}")
        return mask

    def _feedback_units(self) -> np.ndarray | None:
        """``[n, m]`` each feedback gain's unit (action units per standard deviation): ``h_i / sqrt(m)``, ``h_i`` half
        the env's action box (1 where it is unbounded); None in open loop."""
        if self.settings.feedback is None:
            return None
        low = np.asarray(self.env_action_space.low, dtype=np.float64)
        high = np.asarray(self.env_action_space.high, dtype=np.float64)
        half = np.where(np.isfinite(high - low) & (high > low), (high - low) / 2.0, 1.0)
        m = int(self._flat_space.shape[0])
        return np.repeat(half[:, None] / np.sqrt(m), m, axis=1)

    def _reference_feedback(self) -> LinearFeedback:
        """The feedback standardised on the observations of one ``a = 0`` episode from reset seed
        :data:`FEEDBACK_REFERENCE_SEED` (the reset observation and every step's)."""
        observation, _ = self.env.reset(seed=FEEDBACK_REFERENCE_SEED)
        start = self._joint_state()
        q_des, qd_des = self.desired_trajectory(self.theta0, *start)
        run = self._track(start, q_des, qd_des, observation=self._flatten(observation))
        return LinearFeedback(run["observations"])

    def _reports_success(self) -> bool:
        """Whether the env reports ``is_success``: in the info of a reset (unseeded) or of one env step after it
        (the action box's point nearest 0). The next episode needs a reset anyway."""
        _, info = self.env.reset()
        if "is_success" in info:
            return True
        low, high = self.env_action_space.low, self.env_action_space.high
        action = np.clip(np.zeros(self.env_action_space.shape), low, high).astype(self.env_action_space.dtype)
        return "is_success" in self.env.step(action)[4]

    # ------------------------------------------------------------------ action <-> parameters
    def action_to_params(self, action: np.ndarray) -> np.ndarray:
        """DMP parameters ``theta [P]`` (float64, groups :attr:`groups`) of an action ``[P]`` (clipped to [-1, 1] as
        in :meth:`step`; NaN or a wrong shape raise ValueError)."""
        return self.param_map.to_params(np.clip(self._check_action(action), -1.0, 1.0))

    def params_to_action(self, theta: np.ndarray) -> np.ndarray:
        """The action ``[P]`` (float32, not clipped) that maps to ``theta [P]``."""
        return self.param_map.to_action(theta)

    def action_time_weights(self) -> np.ndarray:
        """How active each action dimension's parameter is at each env step, ``[T, P]`` in [0, 1] (the weights'
        basis activations at the end of each step; the anchor, the amplitude, the initial conditions and the tempo:
        1)."""
        groups = self.param_map.dmp_groups
        weights = self.dmp.param_time_weights(self.t, groups=groups, transient=0)[1:] if groups \
            else np.zeros((self.n_steps, 0))
        if self.param_map.has_tempo:
            weights = np.hstack([weights, np.ones((self.n_steps, 1))])
        if self.param_map.feedback_shape is not None:
            weights = np.hstack([weights, np.ones((self.n_steps, int(np.prod(self.param_map.feedback_shape))))])
        return weights

    def action_slices(self) -> dict[str, slice]:
        """``{group: slice}`` of the action (the DMP's groups in its order, then ``tempo`` where selected, then
        ``feedback`` with the setting ``feedback="linear"``)."""
        return dict(self.param_map.slices)

    def param_slices(self) -> dict[str, slice]:
        """``{group: slice}`` of ``theta``; the same layout as the action's (:meth:`action_slices`)."""
        return self.action_slices()

    def policy_dmp(self, theta: np.ndarray) -> RhythmicDMP:
        """The DMP of parameters ``theta [P]``: the initial DMP with the selected groups set, its canonical system at
        the tempo of ``theta`` (what :meth:`step` rolls out; ``save_dmp`` keeps the tempo)."""
        params, tempo = self.param_map.split(theta)
        moved = self.dmp.with_params(params, self.param_map.dmp_groups) if self.param_map.dmp_groups \
            else copy.copy(self.dmp)
        if tempo != moved.canonical.tempo:
            if not (np.isfinite(tempo) and tempo > 0.0):
                raise ValueError(f"theta: the tempo must be > 0, got {tempo!r}")
            moved = copy.copy(moved)
            moved.canonical = replace(moved.canonical, tempo=tempo)
        return moved

    def _check_action(self, action: Any) -> np.ndarray:
        return checked_action(action, self.action_space.shape)

    # ------------------------------------------------------------------ rollouts
    def _joint_state(self) -> tuple[np.ndarray, np.ndarray]:
        state = self._read(self.env)
        try:
            q, qd = (np.asarray(part, dtype=np.float64) for part in state)
        except (TypeError, ValueError) as error:
            raise ValueError("joint_state: expected the reader to return (q [d], qd [d])") from error
        expected = getattr(self, "n_joints", None)
        if q.ndim != 1 or qd.shape != q.shape or (expected is not None and q.size != expected):
            raise ValueError(f"joint_state: expected (q, qd) of {expected or 'd'} values each, got shapes {q.shape}, "
                             f"{qd.shape}")
        return q, qd

    def desired_trajectory(self, theta: np.ndarray, q0: np.ndarray | None = None, qd0: np.ndarray | None = None
                           ) -> tuple[np.ndarray, np.ndarray]:
        """Desired joint positions and velocities ``[T + 1, d]`` on :attr:`t` for parameters ``theta [P]``, from
        ``(q0, qd0)`` (default: the state of the last reset)."""
        if q0 is None or qd0 is None:
            if self._start is None:
                raise RuntimeError("call reset() first, or pass the start state (q0, qd0)")
            q0 = self._start[0] if q0 is None else q0
            qd0 = self._start[1] if qd0 is None else qd0
        moved = self.policy_dmp(theta)
        return moved.rollout(self.t, 0, y0=np.asarray(q0, dtype=np.float64), yd0=np.asarray(qd0, dtype=np.float64),
                             tempo=moved.canonical.tempo, return_velocity=True)

    def rollout_path(self, theta: np.ndarray) -> np.ndarray:
        """``[T, d]`` the desired joint path for ``theta [P]`` at the end of each env step, from the last reset."""
        return self.desired_trajectory(theta)[0][1:]

    # ------------------------------------------------------------------ the task contract
    def task_contract(self) -> TaskContract:
        """What the tools may know of this task (:mod:`rdmp_gym.envs.contract`): the episode length
        (``info["env_steps"]``) and the tracking error (``info["tracking_rmse"]``, RMS over the episode after the
        reset state), success where the env reports it, the jerk of the desired joint path (:meth:`executed_path`)
        at the env's step."""
        return TaskContract(name=self.env_name,
                            metrics=(Metric("env_steps", "episode length", unit="steps"),
                                     Metric("tracking_rmse", "tracking error (RMS)", higher_is_better=False,
                                            unit=self._joint_unit())),
                            has_success=self.has_success, smoothness="jerk", dt=self.dt,
                            path_labels=tuple(self.joint_names))

    def _joint_unit(self) -> str:
        """``"rad"`` where every joint is a MuJoCo hinge, ``"m"`` where every one is a slide, else ``""``."""
        if not isinstance(self._read, MujocoJoints):
            return ""
        import mujoco

        kinds = set(self.env.unwrapped.model.jnt_type[self._read.joint_ids].tolist())
        return {int(mujoco.mjtJoint.mjJNT_HINGE): "rad", int(mujoco.mjtJoint.mjJNT_SLIDE): "m"}.get(
            kinds.pop(), "") if len(kinds) == 1 else ""

    def executed_path(self, action: np.ndarray) -> np.ndarray:
        """``[T, d]`` the desired joint path of ``action [n]`` at the end of each env step, from the state of the last
        reset: what the tracking controller follows (:meth:`rollout_path` of :meth:`action_to_params`)."""
        return self.rollout_path(self.action_to_params(action))

    # ------------------------------------------------------------------ gymnasium API
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset the env (``seed`` and ``options`` go to it); the observation is the context."""
        super().reset(seed=seed)
        observation, info = self.env.reset(seed=seed, options=options)
        self._start = self._joint_state()
        self._context = self._observe(observation)
        if self.feedback is not None:
            self._reset_observation = self._flatten(observation)
        return self._context.copy(), info

    def _flatten(self, observation: Any) -> np.ndarray:
        """``[m]`` (float64) the env's observation flattened."""
        return np.asarray(gym.spaces.flatten(self.env.observation_space, observation), dtype=np.float64)

    def _observe(self, observation: Any) -> np.ndarray:
        return self._flatten(observation)[self.context_mask].astype(np.float32)

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """One whole episode with the DMP of ``action``; ``terminated`` is always True (the env's own flags are in
        ``info``: ``env_terminated``, ``env_truncated``, ``terminated_early``)."""
        a = self._check_action(action)
        if self._start is None:
            raise RuntimeError("step: call reset() first; one step is a whole episode, so every step needs a reset")
        theta = self.param_map.to_params(np.clip(a, -1.0, 1.0))
        start, self._start = self._start, None
        q_des, qd_des = self.desired_trajectory(theta, *start)
        gains = self.param_map.feedback_gains(theta)
        run = self._track(start, q_des, qd_des, gains, self._reset_observation if gains is not None else None)
        return self._context.copy(), float(run["step_rewards"].sum()), True, False, self._info(theta, q_des, qd_des,
                                                                                               run)

    def _track(self, start: tuple[np.ndarray, np.ndarray], q_des: np.ndarray, qd_des: np.ndarray,
               gains: np.ndarray | None = None, observation: np.ndarray | None = None) -> dict[str, Any]:
        """Run the env from the joint state ``start`` along the desired states ``[T + 1, d]`` with the controller
        until the episode's end or the env's; the executed states, the env's actions and rewards, its last step.

        ``gains [n, m]`` add :attr:`feedback` of the last flattened observation to each command (from
        ``observation [m]``, the reset's, which it then needs); with ``observation`` the run also keeps every
        flattened observation (``"observations" [used + 1, m]``) and the feedback's part of the commands
        (``"feedback_actions" [used, n]``, zero without gains)."""
        n, d = self.n_steps, self.n_joints
        positions, velocities = np.empty((n + 1, d)), np.empty((n + 1, d))
        positions[0], velocities[0] = start
        rewards = np.zeros(n)
        commands = np.empty((n, *self.env_action_space.shape), dtype=self.env_action_space.dtype)
        clipped = used = 0
        terminated = truncated = False
        seen = None if observation is None else [observation]
        pushes = None if observation is None else np.zeros((n, *self.env_action_space.shape))
        observation, step_info = None, {}
        for k in range(n):
            raw = np.asarray(self.controller(q_des[k + 1], qd_des[k + 1], positions[k], velocities[k]),
                             dtype=np.float64)
            if gains is not None:
                pushes[k] = self.feedback(gains, seen[-1])
                raw = raw + pushes[k]
            command = self._clipped_command(raw)
            clipped += int(np.count_nonzero(command != raw))
            commands[k] = command
            observation, reward, terminated, truncated, step_info = self.env.step(commands[k])
            rewards[k] = float(reward)
            used = k + 1
            positions[used], velocities[used] = self._joint_state()
            if seen is not None:
                seen.append(self._flatten(observation))
            if self._frames is not None and used % self._frame_stride == 0:
                self._frames.append(self._frame())
            if terminated or truncated:
                break
        run = {"positions": positions[:used + 1], "velocities": velocities[:used + 1], "env_actions": commands[:used],
               "clipped": clipped, "step_rewards": rewards[:used].copy(), "env_terminated": bool(terminated),
               "env_truncated": bool(truncated), "last_observation": observation, "env_info": step_info}
        if seen is not None:
            run.update(observations=np.asarray(seen), feedback_actions=pushes[:used])
        return run

    def _clipped_command(self, raw: np.ndarray) -> np.ndarray:
        """The env's command ``[n]`` (float64): the controller's ``raw [n]`` (feedback included) clipped to the env's
        action box; a ValueError where it has the wrong shape or a non-finite value."""
        if raw.shape != self.env_action_space.shape or not np.all(np.isfinite(raw)):
            raise ValueError(f"controller: returned {raw.shape} values (finite: {bool(np.all(np.isfinite(raw)))}); "
                             f"expected {self.env_action_space.shape} finite values")
        return np.clip(raw, self.env_action_space.low, self.env_action_space.high)

    def _info(self, theta: np.ndarray, q_des: np.ndarray, qd_des: np.ndarray, run: dict[str, Any]) -> dict[str, Any]:
        """The episode's ``info`` (see the docs' table)."""
        used = len(run["step_rewards"])
        error = run["positions"] - q_des[:used + 1]
        cost = np.zeros(self.n_steps)
        cost[:used] = -run["step_rewards"]
        info = {"params": theta, "positions": run["positions"], "velocities": run["velocities"],
                "desired_positions": q_des, "desired_velocities": qd_des, "tracking_error": error,
                "tracking_rmse": float(np.sqrt(np.mean(error[1:] ** 2))) if used else 0.0,
                "env_actions": run["env_actions"], "clipped_fraction": run["clipped"] / max(run["env_actions"].size, 1),
                "env_steps": used, "step_rewards": run["step_rewards"], "cost_trace": cost,
                "env_terminated": run["env_terminated"], "env_truncated": run["env_truncated"],
                "terminated_early": used < self.n_steps, "last_observation": run["last_observation"],
                "env_info": run["env_info"], "valid": True}
        if "is_success" in run["env_info"]:
            info["is_success"] = bool(run["env_info"]["is_success"])
        if "feedback_actions" in run:
            info["feedback_actions"] = run["feedback_actions"]
        return info

    # ------------------------------------------------------------------ rendering
    def render(self) -> Any:
        """The step-based env's frame (as it renders after the last env step)."""
        return self.env.render()

    def can_record(self) -> bool:
        """Whether :meth:`record_episode` can write a video: the env renders RGB frames (it was made with
        ``render_mode="rgb_array"``, e.g. ``make_blackbox(env_id, render_mode="rgb_array")``). Cheap: nothing runs."""
        return getattr(self.env, "render_mode", None) == "rgb_array"

    def record_episode(self, action: np.ndarray, path: str | Path, fps: float | None = None
                       ) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """``step(action)`` while capturing the env's frames (the reset state, then every k-th env step, at most
        :data:`VIDEO_FPS` frames per simulated second), then write them to a video at ``path`` (``.mp4`` or
        ``.gif``; ``fps`` default: real time). Returns the step's result.

        Raises:
            ValueError: the env does not render RGB frames (:meth:`can_record`), or a frame is not ``[H, W, 3]``.
        """
        if not self.can_record():
            raise ValueError(f"render_mode: recording needs the env made with render_mode='rgb_array' "
                             f"(make_blackbox(env_id, render_mode='rgb_array')), got "
                             f"{getattr(self.env, 'render_mode', None)!r}")
        from ..recording import write_video

        self._check_action(action)
        if self._start is None:
            raise RuntimeError("record_episode: call reset() first; one step is a whole episode")
        self._frame_stride = max(1, round(1.0 / (VIDEO_FPS * self.dt)))
        self._frames = [self._frame()]
        try:
            result = self.step(action)
            frames = self._frames
        finally:
            self._frames = None
        write_video(frames, path, fps=1.0 / (self._frame_stride * self.dt) if fps is None else fps)
        return result

    def _frame(self) -> np.ndarray:
        frame = np.asarray(self.env.render())
        if frame.ndim != 3 or frame.shape[2] != 3:
            raise ValueError(f"render_mode: expected the env's render() to give RGB frames [H, W, 3], got shape "
                             f"{frame.shape}")
        return frame

    def close(self) -> None:
        self.env.close()
        super().close()

    def __repr__(self) -> str:
        return (f"RhythmicBlackBoxWrapper({self.env}, joints={self.n_joints}, groups={self.groups}, "
                f"steps={self.n_steps}, dt={self.dt:g})")


def make_blackbox(env_id: str, *, env_kwargs: Mapping[str, Any] | None = None, render_mode: str | None = None,
                  settings: BlackBoxSettings | None = None, **overrides: Any) -> RhythmicBlackBoxWrapper:
    """``gym.make(env_id, **env_kwargs)`` wrapped in a :class:`RhythmicBlackBoxWrapper` with ``settings`` and the
    ``overrides`` by name; what neither gives comes from the env's entry in
    :data:`~rdmp_gym.envs.blackbox.defaults.ENV_DEFAULTS` (e.g. ``Swimmer``'s gains and pattern), else from its
    MuJoCo model (:func:`~rdmp_gym.envs.blackbox.defaults.model_defaults`), so ``make_blackbox("Hopper-v5")``
    needs no setting.

    Registered as ``rdmp_gym/RhythmicBlackBox-v0`` when :mod:`rdmp_gym.envs.blackbox` is imported, so
    ``gym.make("rdmp_gym.envs.blackbox:rdmp_gym/RhythmicBlackBox-v0", env_id="Swimmer-v5")`` builds it too.
    """
    kwargs = dict(env_kwargs or {})
    if render_mode is not None:
        kwargs["render_mode"] = render_mode
    env = gym.make(env_id, **kwargs)
    try:
        return RhythmicBlackBoxWrapper(env, settings, **overrides)
    except BaseException:
        env.close()
        raise


#: the settings of :class:`RhythmicBlackBoxWrapper` (the fields of :class:`BlackBoxSettings`), which
#: :func:`split_settings` takes out of an env's keywords
WRAPPER_SETTINGS = BlackBoxSettings.names()


def _env_keywords(env_id: str) -> set[str] | None:
    """The keywords ``gym.make(env_id, ...)`` takes: ``gym.make``'s own and the named parameters of the entry point
    (for a class: of every ``__init__`` along its MRO); None where they cannot be told (a function with
    ``**kwargs``)."""
    spec = find_spec(env_id)
    creator = gym.envs.registration.load_env_creator(spec.entry_point) if isinstance(spec.entry_point, str) \
        else spec.entry_point
    own = {key for key in inspect.signature(gym.make).parameters if key not in ("id", "kwargs")}
    functions = [klass.__dict__["__init__"] for klass in creator.__mro__ if "__init__" in klass.__dict__] \
        if inspect.isclass(creator) else [creator]
    names: set[str] = set()
    for function in functions:
        try:
            parameters = inspect.signature(function).parameters.values()
        except (TypeError, ValueError):
            continue
        if not inspect.isclass(creator) and any(p.kind is p.VAR_KEYWORD for p in parameters):
            return None
        names |= {p.name for p in parameters if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)}
    return (names - {"self"}) | own | set(spec.kwargs or {})


def split_settings(env_id: str, settings: Mapping[str, Any] | None) -> tuple[dict[str, Any], dict[str, Any]]:
    """``settings`` (e.g. ``rdmp-gym train --env-option KEY VALUE`` on a step-based env) taken apart: the black-box
    wrapper's (names in :data:`WRAPPER_SETTINGS`, e.g. ``p_gains``, ``groups``, ``duration``) and the keywords for
    ``gym.make(env_id, ...)`` (the rest). A name that is neither a wrapper setting nor a keyword of the env is a
    ValueError naming it (where the env's keywords can be told from its signature)."""
    settings = dict(settings or {})
    wrapper = {key: value for key, value in settings.items() if key in WRAPPER_SETTINGS}
    env_part = {key: value for key, value in settings.items() if key not in WRAPPER_SETTINGS}
    known = _env_keywords(env_id)
    unknown = sorted(set(env_part) - known) if known is not None else []
    if unknown:
        raise ValueError(f"env_kwargs: {unknown[0]!r} is neither a setting of the rhythmic black-box wrapper "
                         f"({', '.join(WRAPPER_SETTINGS)}) nor a keyword of {env_id} ({', '.join(sorted(known))})")
    return wrapper, env_part
