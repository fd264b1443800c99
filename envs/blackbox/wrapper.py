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

The names follow fancy_gym's ``BlackBoxWrapper`` where they fit (``duration``, ``context_mask``, a tracking
controller with ``p_gains``/``d_gains``). It is a :class:`gymnasium.Env` that holds the step-based env as
``.env`` rather than a ``gymnasium.Wrapper``: the learners of :mod:`rdmp_gym.agents` find the episodic methods
(``action_to_params``, ``params_to_action``, ``action_time_weights``) on ``env.unwrapped``, which is this object.
"""

from __future__ import annotations

import copy
import inspect
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import replace
from typing import Any

import gymnasium as gym
import numpy as np

from rdmp_gym import Demonstration, RhythmicDMP

from ..action import checked_action
from ..specs import find_spec
from .controller import JointReader, MujocoJoints, TrackingController, make_controller
from .defaults import default_demonstration, env_defaults
from .params import JointParameterMap

__all__ = ["DEFAULT_GROUPS", "WRAPPER_SETTINGS", "RhythmicBlackBoxWrapper", "make_blackbox", "split_settings"]

#: the parameter groups in the action by default: the cycle's shape, its amplitude and the posture it is centred on
DEFAULT_GROUPS = ("periodic", "amplitude", "anchor")


class RhythmicBlackBoxWrapper(gym.Env):
    """Episodic black-box env: a rhythmic joint-space DMP tracked on a step-based env for one whole episode.

    Args:
        env: a step-based Gymnasium env with a continuous ``Box`` action space (e.g. ``gym.make("Swimmer-v5")``).
        groups: the DMP parameter groups in the action (:data:`DEFAULT_GROUPS`; also ``transient``, ``initial``, and
            ``tempo``: the cycle's speed as one more action dimension, ``tempo = 1 + 0.5 a``).
        duration: the episode (s); default the env's time limit (``spec.max_episode_steps * dt``). It must fit in the
            time limit and be a whole number of env steps.
        controller: ``"pd"`` (joint torques), ``"position"`` or ``"velocity"`` (joint targets), or a callable
            ``(q_des, qd_des, q, qd) -> action`` (:mod:`~rdmp_gym.envs.blackbox.controller`).
        p_gains, d_gains: the built-in controllers' gains (a number or one per joint, in action units per joint
            unit): ``"pd"`` needs ``p_gains`` (``d_gains`` default 0); ``"velocity"`` takes ``p_gains`` (default 0).
        context_mask: ``[o]`` booleans that select the context (the observation) from the flattened reset
            observation; None: all of it.
        demonstration: a joint-space :class:`~rdmp_gym.Demonstration` ``Y [L, d]`` (d joints, the transient start
            then at least two cycles) that the initial DMP is fitted to; None: the default pattern.
        dmp: a fitted :class:`~rdmp_gym.RhythmicDMP` with ``d`` dimensions to start from (instead of a fit).
        n_periodic, n_transient: basis functions of the fitted DMP.
        period, amplitude, phases: the default pattern without demonstration (s; joint units, a number or one per
            joint; per joint phases in rad, or a number: the lag between neighbouring joints, default pi/2).
        posture: ``[d]`` the default pattern's anchor; default the MuJoCo env's ``init_qpos`` at the joints, else the
            joint positions after ``env.reset(seed=0)``.
        joint_state: ``reader(env) -> (q [d], qd [d])``; default for MuJoCo envs: the joints of the actuators
            (:class:`~rdmp_gym.envs.blackbox.controller.MujocoJoints`).
        dt: seconds per env step; default ``env.unwrapped.dt``.
        scales: ``{group: frac}`` action scales over :data:`~rdmp_gym.envs.blackbox.defaults.BLACKBOX_SCALES`.
        fit_kwargs: settings of :meth:`RhythmicDMP.fit <rdmp_gym.RhythmicDMP.fit>` (``period``, ``alpha_z``, ...).

    Raises:
        ValueError: naming the argument, for an env it cannot drive (a discrete action space, no joint state to
            track, no step length or time limit) and for inconsistent settings.
    """

    def __init__(self, env: gym.Env, *, groups: Iterable[str] | str = DEFAULT_GROUPS, duration: float | None = None,
                 controller: str | TrackingController = "pd", p_gains: float | Sequence[float] | None = None,
                 d_gains: float | Sequence[float] | None = None, context_mask: Sequence[bool] | None = None,
                 demonstration: Demonstration | None = None, dmp: RhythmicDMP | None = None, n_periodic: int = 10,
                 n_transient: int = 10, period: float = 1.0, amplitude: float | Sequence[float] = 0.2,
                 phases: float | Sequence[float] | None = None, posture: Sequence[float] | None = None,
                 joint_state: JointReader | None = None, dt: float | None = None,
                 scales: Mapping[str, float] | None = None, fit_kwargs: Mapping[str, Any] | None = None) -> None:
        if not isinstance(env, gym.Env):
            raise TypeError(f"env: expected a gymnasium.Env, got {type(env).__name__}")
        space = env.action_space
        if not isinstance(space, gym.spaces.Box) or len(space.shape) != 1 \
                or not np.issubdtype(space.dtype, np.floating):
            raise ValueError(f"env: the rhythmic black-box wrapper needs a continuous Box action space (one float per "
                             f"actuator), got {space}")
        self.env = env
        self.env_action_space = space
        self.dt = self._step_length(env, dt)
        self.n_steps = self._steps(env, duration)
        #: ``[T + 1]`` the env step grid (s): the reset state at 0, the end of env step k at ``t[k + 1]``
        self.t = np.arange(self.n_steps + 1) * self.dt
        self._read, mujoco = self._reader(env, joint_state)
        self.posture = self._posture(env, posture, mujoco)
        self.n_joints = int(self.posture.size)
        self.controller = make_controller(controller, self.n_joints, int(space.shape[0]), p_gains, d_gains)
        self.dmp = self._initial_dmp(dmp, demonstration, n_periodic, n_transient, period, amplitude, phases,
                                     fit_kwargs)
        self.groups = (groups,) if isinstance(groups, str) else tuple(groups)
        self.param_map = JointParameterMap(self.dmp, self.groups, scales, self._cycle_motion())
        self.theta0 = self.param_map.theta0.copy()
        self.action_space = gym.spaces.Box(-1.0, 1.0, (self.param_map.size,), np.float32)
        self._flat_space = gym.spaces.flatten_space(env.observation_space)
        self.context_mask = self._mask(context_mask)
        self.observation_space = gym.spaces.Box(self._flat_space.low[self.context_mask].astype(np.float32),
                                                self._flat_space.high[self.context_mask].astype(np.float32),
                                                dtype=np.float32)
        self.metadata = dict(getattr(env, "metadata", {}))
        self.render_mode = getattr(env, "render_mode", None)
        self._start: tuple[np.ndarray, np.ndarray] | None = None
        self._context = np.zeros(int(self.context_mask.sum()), dtype=np.float32)

    # ------------------------------------------------------------------ construction
    @staticmethod
    def _step_length(env: gym.Env, dt: float | None) -> float:
        value = getattr(env.unwrapped, "dt", None) if dt is None else dt
        if value is None:
            raise ValueError("dt: the env has no `dt` (seconds per env step); pass dt=...")
        value = float(value)
        if not (np.isfinite(value) and value > 0.0):
            raise ValueError(f"dt: expected seconds per env step > 0, got {value!r}")
        return value

    def _steps(self, env: gym.Env, duration: float | None) -> int:
        limit = getattr(getattr(env, "spec", None), "max_episode_steps", None)
        if duration is None:
            if limit is None:
                raise ValueError("duration: the env has no time limit (spec.max_episode_steps) to take the episode's "
                                 "length from; pass duration=... (s)")
            return int(limit)
        duration = float(duration)
        steps = round(duration / self.dt)
        if not np.isfinite(duration) or steps < 1 or abs(steps * self.dt - duration) > 1e-6 * max(duration, 1.0):
            raise ValueError(f"duration: expected a whole number (>= 1) of env steps of {self.dt:g} s, "
                             f"got {duration!r}")
        if limit is not None and steps > limit:
            raise ValueError(f"duration: {duration:g} s is {steps} env steps, more than the env's time limit of "
                             f"{limit} steps ({limit * self.dt:g} s)")
        return int(steps)

    @staticmethod
    def _reader(env: gym.Env, joint_state: JointReader | None) -> tuple[Callable, MujocoJoints | None]:
        if joint_state is not None:
            if not callable(joint_state):
                raise ValueError(f"joint_state: expected a callable env -> (q, qd), got {type(joint_state).__name__}")
            return joint_state, None
        if not MujocoJoints.available(env):
            raise ValueError("joint_state: the env has no MuJoCo model and data (env.unwrapped.model/.data) to read "
                             "the actuated joints from, so there is no joint state to track; pass "
                             "joint_state=callable(env) -> (q [d], qd [d])")
        joints = MujocoJoints(env)
        return joints, joints

    def _posture(self, env: gym.Env, posture: Sequence[float] | None, mujoco: MujocoJoints | None) -> np.ndarray:
        if posture is None and mujoco is not None:
            posture = mujoco.posture(env)
        if posture is None:
            env.reset(seed=0)
            posture = self._joint_state()[0]
        values = np.asarray(posture, dtype=np.float64)
        if values.ndim != 1 or values.size == 0 or not np.all(np.isfinite(values)):
            raise ValueError(f"posture: expected [d] finite joint positions, got {posture!r}")
        if mujoco is not None and values.size != mujoco.qpos_adr.size:
            raise ValueError(f"posture: expected {mujoco.qpos_adr.size} joint positions (one per actuator), "
                             f"got {values.size}")
        return values.copy()

    def _initial_dmp(self, dmp: RhythmicDMP | None, demonstration: Demonstration | None, n_periodic: int,
                     n_transient: int, period: float, amplitude: Any, phases: Any,
                     fit_kwargs: Mapping[str, Any] | None) -> RhythmicDMP:
        if dmp is not None:
            if demonstration is not None:
                raise ValueError("dmp: give a fitted dmp or a demonstration, not both")
            if not isinstance(dmp, RhythmicDMP):
                raise ValueError(f"dmp: expected a RhythmicDMP, got {type(dmp).__name__}")
            if dmp.n_dims != self.n_joints:
                raise ValueError(f"dmp: has {dmp.n_dims} dimensions, the env has {self.n_joints} joints")
            return dmp
        keywords = dict(fit_kwargs or {})
        if demonstration is not None:
            if not isinstance(demonstration, Demonstration):
                raise ValueError("demonstration: expected a rdmp_gym.Demonstration, got "
                                 f"{type(demonstration).__name__}")
            if demonstration.n_dims != self.n_joints:
                raise ValueError(f"demonstration: has {demonstration.n_dims} dimensions, the env has {self.n_joints} "
                                 "joints (one DMP dimension per actuated joint)")
            return RhythmicDMP.fit(demonstration, n_periodic, n_transient, **keywords)
        demo, segmentation = default_demonstration(self.posture, period, amplitude, phases)
        keywords.setdefault("segmentations", [segmentation])
        keywords.setdefault("period", segmentation.period)
        return RhythmicDMP.fit(demo, n_periodic, n_transient, **keywords)

    def _cycle_motion(self) -> np.ndarray:
        """``[d]`` each joint's peak-to-peak motion over the initial DMP's first cycle after the transient."""
        start = self.dmp.transients[0].length
        t = np.linspace(0.0, start + self.dmp.period, 400)
        path = self.dmp.rollout(t)[t >= start]
        return np.ptp(path, axis=0)

    def _mask(self, context_mask: Sequence[bool] | None) -> np.ndarray:
        size = int(self._flat_space.shape[0])
        if context_mask is None:
            return np.ones(size, dtype=bool)
        mask = np.asarray(context_mask)
        if mask.dtype != bool or mask.shape != (size,):
            raise ValueError(f"context_mask: expected {size} booleans (one per entry of the env's flattened "
                             f"observation), got {mask.dtype} array of shape {mask.shape}")
        return mask.copy()

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
        return weights

    def action_slices(self) -> dict[str, slice]:
        """``{group: slice}`` of the action (the DMP's groups in its order, then ``tempo`` where selected)."""
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

    # ------------------------------------------------------------------ gymnasium API
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset the env (``seed`` and ``options`` go to it); the observation is the context."""
        super().reset(seed=seed)
        observation, info = self.env.reset(seed=seed, options=options)
        self._start = self._joint_state()
        self._context = self._observe(observation)
        return self._context.copy(), info

    def _observe(self, observation: Any) -> np.ndarray:
        flat = np.asarray(gym.spaces.flatten(self.env.observation_space, observation), dtype=np.float64)
        return flat[self.context_mask].astype(np.float32)

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """One whole episode with the DMP of ``action``; ``terminated`` is always True (the env's own flags are in
        ``info``: ``env_terminated``, ``env_truncated``, ``terminated_early``)."""
        a = self._check_action(action)
        if self._start is None:
            raise RuntimeError("step: call reset() first; one step is a whole episode, so every step needs a reset")
        theta = self.param_map.to_params(np.clip(a, -1.0, 1.0))
        q_start, qd_start = self._start
        q_des, qd_des = self.desired_trajectory(theta, q_start, qd_start)
        self._start = None
        low, high = self.env_action_space.low, self.env_action_space.high
        n, d = self.n_steps, self.n_joints
        positions, velocities = np.empty((n + 1, d)), np.empty((n + 1, d))
        positions[0], velocities[0] = q_start, qd_start
        rewards = np.zeros(n)
        commands = np.empty((n, *self.env_action_space.shape), dtype=self.env_action_space.dtype)
        clipped = 0
        terminated = truncated = False
        observation, step_info = None, {}
        used = 0
        for k in range(n):
            raw = np.asarray(self.controller(q_des[k + 1], qd_des[k + 1], positions[k], velocities[k]),
                             dtype=np.float64)
            if raw.shape != self.env_action_space.shape or not np.all(np.isfinite(raw)):
                raise ValueError(f"controller: returned {raw.shape} values (finite: {bool(np.all(np.isfinite(raw)))}); "
                                 f"expected {self.env_action_space.shape} finite values")
            command = np.clip(raw, low, high)
            clipped += int(np.count_nonzero(command != raw))
            commands[k] = command
            observation, reward, terminated, truncated, step_info = self.env.step(commands[k])
            rewards[k] = float(reward)
            used = k + 1
            positions[used], velocities[used] = self._joint_state()
            if terminated or truncated:
                break
        error = positions[:used + 1] - q_des[:used + 1]
        total = float(rewards[:used].sum())
        cost = np.zeros(n)
        cost[:used] = -rewards[:used]
        info = {"params": theta, "positions": positions[:used + 1], "velocities": velocities[:used + 1],
                "desired_positions": q_des, "desired_velocities": qd_des, "tracking_error": error,
                "tracking_rmse": float(np.sqrt(np.mean(error[1:] ** 2))) if used else 0.0,
                "env_actions": commands[:used], "clipped_fraction": clipped / max(commands[:used].size, 1),
                "env_steps": used, "step_rewards": rewards[:used].copy(), "cost_trace": cost,
                "env_terminated": bool(terminated), "env_truncated": bool(truncated), "terminated_early": used < n,
                "last_observation": observation, "env_info": step_info, "valid": True}
        if "is_success" in step_info:
            info["is_success"] = bool(step_info["is_success"])
        return self._context.copy(), total, True, False, info

    def render(self) -> Any:
        """The step-based env's frame (as it renders after the last env step)."""
        return self.env.render()

    def close(self) -> None:
        self.env.close()
        super().close()

    def __repr__(self) -> str:
        return (f"RhythmicBlackBoxWrapper({self.env}, joints={self.n_joints}, groups={self.groups}, "
                f"steps={self.n_steps}, dt={self.dt:g})")


def make_blackbox(env_id: str, *, env_kwargs: Mapping[str, Any] | None = None, render_mode: str | None = None,
                  **settings: Any) -> RhythmicBlackBoxWrapper:
    """``gym.make(env_id, **env_kwargs)`` wrapped in a :class:`RhythmicBlackBoxWrapper` with ``settings`` over the
    env's entry in :data:`~rdmp_gym.envs.blackbox.defaults.ENV_DEFAULTS` (e.g. ``Swimmer``'s gains and pattern).

    Registered as ``rdmp_gym/RhythmicBlackBox-v0`` when :mod:`rdmp_gym.envs.blackbox` is imported, so
    ``gym.make("rdmp_gym.envs.blackbox:rdmp_gym/RhythmicBlackBox-v0", env_id="Swimmer-v5")`` builds it too.
    """
    kwargs = dict(env_kwargs or {})
    if render_mode is not None:
        kwargs["render_mode"] = render_mode
    env = gym.make(env_id, **kwargs)
    try:
        return RhythmicBlackBoxWrapper(env, **{**env_defaults(env_id), **settings})
    except BaseException:
        env.close()
        raise


#: the settings of :class:`RhythmicBlackBoxWrapper` (its keywords but ``env``), which :func:`split_settings` takes
#: out of an env's keywords
WRAPPER_SETTINGS = tuple(name for name in inspect.signature(RhythmicBlackBoxWrapper.__init__).parameters
                         if name not in ("self", "env"))


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
