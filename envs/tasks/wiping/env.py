"""``rdmp_gym/ArmarWipe-v3`` (and v1, v2, ``PandaWipe-v3``): episodic table wiping with a rhythmic DMP.

The wiping task's episodic face: it reads the task from its description
(:class:`~rdmp_gym.envs.tasks.wiping.task.WipingTask`, :attr:`ArmarWipeEnv.task`: scene, context, DMP, action
layout, plan, judgement) and runs the simulation core with the task's hook. What each version changes (v2: the
travelling pattern, solvable contexts, the smoothness measure, executable success; v3: the composed scene of any
robot and a smooth-path success) is listed in :mod:`rdmp_gym.envs.tasks.wiping.versions`; ``version`` selects it
(default 3, the current task).

One ``step`` is one whole DMP rollout (``terminated=True, truncated=False``):

1. the action ``a in [-1, 1]^n`` becomes DMP parameters ``theta = theta_imitation + scale * a`` (plus, for
   the last dimension, ``approach``, a fixed direction that lifts the approach:
   :mod:`rdmp_gym.envs.tasks.wiping.approach`);
2. the DMP, anchored at the dirt patch centre and started at the sponge start of the context, gives
   the sponge path ``P [T, 3]`` in the table frame (x, y on the table, z above it);
3. the path is checked (finite, inside the workspace, reachable by the IK with the sponge flat on the
   tilted table, joint speeds): an invalid one returns a graded penalty at once, ``info["valid"] = False``;
4. otherwise MuJoCo simulates it at the control rate with differential-IK joint targets and online
   wrist-force adaptation of the pressing depth along the actual table normal (the table height is
   unknown to the controller; its tilt is known from the context); a cup may stand in the approach;
5. the reward sums the terms of :mod:`rdmp_gym.envs.tasks.wiping.reward`, all in ``info["reward_terms"]``, and
   ``info["cost_trace"]`` gives the per-control-step cost for PI² (it sums to ``-reward``;
   ``info["cost_terms"]`` splits it by term);
   ``info["is_success"]``: coverage >= 0.95, force in band >= 90 % of the wiping phase, no collision
   (arm on the table, arm on the robot's body), the cup neither touched nor moved, a valid episode;
   ``info["failure_causes"]`` names the criteria an episode misses (:func:`failure_causes`, empty for a success).

Rendering: ``render_mode="rgb_array"`` renders offscreen with ``mujoco.Renderer``; on a headless
machine set ``MUJOCO_GL=egl`` (or ``osmesa``) before importing mujoco. Because an episode is a single
step, :meth:`ArmarWipeEnv.record_episode` (or ``record_frames=True``) captures frames inside it.
"""

from __future__ import annotations

import logging
import warnings
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np

from ...action import checked_action
from ...controller import ForceAdaptation, JointTargetPlan
from ...ik import IKResult
from ...recording import SceneRenderer, write_video
from ...viewer import HumanViewer
from ..description import TaskPlan, ToolPath
from .clearance import Cup
from .context import SIZE as CONTEXT_SIZE
from .context import Context
from .info import void_statistics
from .reward import Smoothness, invalid_reward
from .settings import EnvConfig, RenderConfig
from .simulation import DirtField, SimulationSettings, WipeTrace, simulate_wipe
from .task import (
    WipeRecord,
    WipingTask,
    _workspace_excess,
    episode_success,
    failure_causes,
    outcome,
)

__all__ = ["ArmarWipeEnv", "deprecated_v0", "episode_success", "failure_causes", "outcome"]

logger = logging.getLogger(__name__)

#: The task's attributes the env has as its own (the same objects; the task is :attr:`ArmarWipeEnv.task`).
_TASK_ATTRIBUTES = ("task_version", "robot", "dmp", "groups", "_approach", "_anchor_z", "scene", "frame_skip", "dt",
                    "control_rate", "n_steps", "times", "periodic", "action_map", "force_band", "adaptation_settings",
                    "force_learning", "reward_settings", "reward_weights", "cell_size", "limit_margin", "ik_tolerance",
                    "max_joint_speed", "wear_rate", "penetration_limit", "obstacle", "context_spec", "ik",
                    "cup_clearance", "_engage")

class ArmarWipeEnv(gym.Env):
    """Episodic wiping env; see the module docstring.

    The settings come as one :class:`~rdmp_gym.envs.tasks.wiping.settings.EnvConfig` (``config``), as keywords
    (``gym.make``'s
    way), or both (the keywords change the config); every setting is validated for type and meaning, with an error
    that names it, and :attr:`config` saves to and loads from JSON.

    Args:
        config: all settings at once (default: ``EnvConfig()``).
        robot: the robot, a registered name (``"armar3"``, ``"panda"``) or a ``RobotDescription``
            (:mod:`rdmp_gym.envs.robots`).
        style: synthetic demonstration style 1..4 (1/2 circle, 3/4 figure-eight; 2/4 complex approach).
        demonstration: a user ``rdmp_gym.Demonstration`` ``Y [L, 3]`` in the table frame, in metres: x, y on
            the table, z above its surface (overrides ``style``; checked against the workspace before fitting).
        dmp: a saved DMP (a ``dmp.json`` path, e.g. a run's refined DMP, or a ``RhythmicDMP``) used as the
            imitation without fitting (overrides ``style``; excludes ``demonstration``).
        n_periodic, n_transient, fit_method: DMP fit settings (default the core's ``"trajectory"`` fit: the
            smoothest imitation, half the jerk of ``"ridge"``).
        groups: parameter groups in the action (default periodic weights, transient weights, initial condition,
            amplitude, and ``"approach"``: one dimension that raises or lowers the approach as a whole, see
            :mod:`rdmp_gym.envs.tasks.wiping.approach`; it needs ``"transient"``; v2 adds ``"sweep"``: the anchor
            travels over the patch, two action dimensions ``sweep_x``, ``sweep_y``, see
            :mod:`rdmp_gym.envs.tasks.wiping.coverage`).
        scales: per-group action scales (see :mod:`rdmp_gym.envs.action`; ``approach``: lift in m at +1).
        n_periods: periods of the pattern after the transient (default 4 in v1, 7 in v2); ``duration`` (s)
            overrides it.
        control_rate: control frequency (Hz); ``frame_skip`` (physics steps per control step) overrides it.
        timestep: physics step (s; default the model's 2 ms).
        target_force: normal force to hold while wiping (N) (controller and reward).
        force_band: (min, max) normal force (N) that wipes a cell; the max is also the excess-force limit.
        force_sigma: width (N) of the force-closeness reward.
        reward_weights: ``{term: weight}`` overrides (see :mod:`rdmp_gym.envs.tasks.wiping.reward`).
        adaptation: adapt the pressing depth from the wrist force (``False``: feed-forward preload only).
        admittance_gain: depth rate per newton of force error (m/(N s)).
        force_learning: also learn the pressing depth as a periodic function of the DMP's phase and feed it
            forward on the next periods (Gams et al. 2010; :mod:`rdmp_gym.envs.tasks.wiping.force_learning`); ``True``
            or a ``ForceProfileSettings``.
        context_ranges: ``{field: (low, high)}`` sampling ranges (see :mod:`rdmp_gym.envs.tasks.wiping.context`).
        obstacle: contexts may put a cup in the approach corridor (``False``: never).
        obstacle_probability: share of drawn contexts with a cup (where one fits).
        cell_size: dirt cell side (m).
        wear_rate: Preston coefficient of the dirt (1/(Pa m); see :mod:`rdmp_gym.envs.tasks.wiping.simulation`).
        penetration_limit: penetration (m) of a robot geom into the robot's body or (other than the
            sponge) into the table beyond which the episode is invalid (reason ``"penetration"``).
        limit_margin: distance to a joint limit (rad) that counts as "at the limit".
        ik_tolerance: (position m, angle rad) IK residuals beyond which a path is unreachable.
        max_joint_speed: joint speed (rad/s) of the planned path beyond which it is invalid (default: the robot's).
        xml_file: a hand-merged scene MJCF (default: the robot's own scene;
        :class:`~rdmp_gym.envs.tasks.wiping.scene.WipeScene`).
        render_mode: ``None``, ``"rgb_array"`` (RGB frames), ``"depth_array"`` (depth in m) or ``"human"``
            (MuJoCo's viewer, following every control step; needs a display); width, height, camera: of the
            rendered frames.
        record_frames: capture frames during every step into :attr:`frames`; frame_stride: every how
            many control steps.
        version: the task version, 1, 2 or 3 (:mod:`rdmp_gym.envs.tasks.wiping.versions`; default 3, the current task as
            ``rdmp_gym/ArmarWipe-v3`` makes it); ``gym.make`` of an id sets its own.
        cup_clearance: execute every path with a clearance term that keeps the hand (fingers, thumb, palm,
            sponge) this many metres from the cup's side (:class:`~rdmp_gym.envs.tasks.wiping.clearance.CupClearance`,
            or one given); ``None`` (default): the path as commanded. The reward and the success criteria are the same;
            ``info["clearance_push"]`` gives the largest push of the path (m).
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["human", "rgb_array", "depth_array"], "render_fps": 25}

    def __init__(self, config: EnvConfig | None = None, **settings: Any):
        super().__init__()
        config = EnvConfig.from_kwargs(**settings) if config is None else config.replace(**settings)
        #: every setting of this env (:class:`~rdmp_gym.envs.tasks.wiping.settings.EnvConfig`; saves to and loads
        #: from JSON)
        self.config = config
        #: the task (:class:`~rdmp_gym.envs.tasks.wiping.task.WipingTask`): its scene, DMP, action layout, context
        #: and judgement
        self.task = WipingTask(config)
        for name in _TASK_ATTRIBUTES:          # what the env has read of its task since v1, as its own attributes
            setattr(self, name, getattr(self.task, name))
        self.render_mode = config.render.render_mode
        self._lead = self.scene.servo_lead()
        self.action_space = gym.spaces.Box(-1.0, 1.0, shape=(self.action_map.size,), dtype=np.float32)
        self.observation_space = gym.spaces.Box(self.context_spec.bound_low.astype(np.float32),
                                                self.context_spec.bound_high.astype(np.float32),
                                                shape=(CONTEXT_SIZE,), dtype=np.float32)
        self._set_rendering(config.render)
        self.context: Context | None = None
        #: the dirt cells' centres on the actual table, ``[N, 3]`` (world), drawn at reset
        self.dirt_cells = np.zeros((0, 3))
        #: dirt left per cell ``[N]`` in [0, 1] (after the last episode; what ``render`` shows)
        self.dirt_left = np.zeros(0)
        self._imitation_jerk: float | None = None

    # ------------------------------------------------------------------ construction stages
    def _set_rendering(self, render: RenderConfig) -> None:
        self.frame_stride = render.frame_stride
        self.metadata = {**self.metadata, "render_fps": max(1, round(self.control_rate / self.frame_stride))}
        self._render_args = (render.width, render.height, render.camera)
        self._renderer: SceneRenderer | None = None
        self._viewer = HumanViewer(self.scene) if render.render_mode == "human" else None
        if render.render_mode in ("rgb_array", "depth_array") or render.record_frames:
            self._renderer = SceneRenderer(self.scene, *self._render_args)
        self.record_frames = render.record_frames
        #: record the sponge-table force at every physics step into ``info["fine_force_trace"]``
        self.fine_force = False
        self.frames: list[np.ndarray] = []

    def force_adaptation(self) -> ForceAdaptation:
        """A fresh force controller of this env (:meth:`WipingTask.force_adaptation
        <rdmp_gym.envs.tasks.wiping.task.WipingTask.force_adaptation>`)."""
        return self.task.force_adaptation()

    @property
    def success_joint_accel(self) -> float | None:
        """The peak joint acceleration (rad/s²) that ``is_success`` allows (None: not checked, v1)."""
        return self.task.success_joint_accel

    @property
    def simulation_settings(self) -> SimulationSettings:
        """The simulation core's settings of this env
        (:class:`~rdmp_gym.envs.tasks.wiping.simulation.SimulationSettings`)."""
        return SimulationSettings(limit_margin=self.limit_margin, fine_force=self.fine_force,
                                  cup_from_touch=self.task_version.cup_from_touch)

    # ------------------------------------------------------------------ action <-> parameters
    def action_to_params(self, action: np.ndarray) -> np.ndarray:
        """DMP parameters ``theta [P]`` (float64, groups :attr:`groups`) of an action ``[n_action]`` (clipped to
        [-1, 1] as in :meth:`step`; NaN or a wrong shape raise ValueError). ``n_action = P + 1`` with the
        ``approach`` dimension (last), else P."""
        return self.action_map.to_params(self._check_action(action))

    def params_to_action(self, theta: np.ndarray) -> np.ndarray:
        """An action ``[n_action]`` (float32, unclipped) that maps to ``theta [P]`` (0 in the approach dimension)."""
        return self.action_map.to_action(theta)

    def action_time_weights(self) -> np.ndarray:
        """How active each action dimension's parameter is at each control step, ``[T_ctrl, n_action]`` in [0, 1]."""
        return self.task.action_time_weights()

    def _check_action(self, action: Any) -> np.ndarray:
        return np.clip(checked_action(action, self.action_space.shape), -1.0, 1.0)

    # ------------------------------------------------------------------ gym API
    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        """Draw a context (``options`` can fix any field; see :mod:`rdmp_gym.envs.tasks.wiping.context`) and put the
        robot at rest with the sponge at the start position."""
        super().reset(seed=seed)
        if options is not None and not isinstance(options, Mapping):
            raise ValueError(f"options: expected a dict, got {type(options).__name__}")
        context = self.task.sample_context(self.np_random, options)
        self.context = context
        self.task.place(self.scene.model, context)
        self.dirt_cells = self.task.dirt_cells(context)
        self.dirt_left = np.ones(len(self.dirt_cells))
        self._imitation_jerk = None
        start = self.solve_path(context.sponge_start[None])
        self.scene.set_arm_state(start.q[0])
        self.frames = []
        return self._observation(), {"context": context.vector()}

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict]:
        """Run one whole wiping episode with the DMP parameters of ``action`` ``[n]`` (clipped to [-1, 1];
        NaN, infinite values or a wrong shape raise ValueError). Always ``terminated=True, truncated=False``."""
        if self.context is None:
            raise RuntimeError("call reset() before step()")
        a = self._check_action(action)
        theta = self.action_map.to_params(a)
        self.frames = []
        reward, info = self._evaluate(theta)
        return self._observation(), reward, True, False, info

    def render(self) -> np.ndarray | None:
        """The current state: RGB frame ``[height, width, 3]`` uint8 (``"rgb_array"``), depth ``[height, width]``
        float32 in m (``"depth_array"``), or None after updating the viewer (``"human"``)."""
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode='rgb_array' to the env")
            return None
        if self._viewer is not None:
            self._viewer.sync()
            return None
        if self.render_mode == "depth_array":
            if self._renderer is None:
                self._renderer = SceneRenderer(self.scene, *self._render_args)
            return self._renderer.render_depth()
        return self._frame()

    def close(self) -> None:
        """Release the renderer (safe to call more than once)."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
        if self._viewer is not None:
            self._viewer.close()

    def record_episode(self, action: np.ndarray, path: str | Path, fps: float | None = None
                       ) -> tuple[np.ndarray, float, bool, bool, dict]:
        """``step(action)`` while capturing frames every ``frame_stride`` control steps, then write them
        to a video at ``path`` (``.mp4`` or ``.gif``). Returns the step's result."""
        recording = self.record_frames
        self.record_frames = True
        try:
            result = self.step(action)
        finally:
            self.record_frames = recording
        write_video(self.frames, path, fps=self.metadata["render_fps"] if fps is None else fps)
        return result

    # ------------------------------------------------------------------ episode
    def context_kind(self, observation: np.ndarray) -> str:
        """The kind of the context ``observation [13]`` (:data:`rdmp_gym.envs.tasks.wiping.context.CONTEXT_KINDS`: a
        cup on the
        approach, a cup beside the patch, no cup on one of the largest patches, no cup), for stratified validation."""
        return self.context_spec.kind(Context.from_vector(np.asarray(observation, dtype=np.float64)))

    def rollout_path(self, theta: np.ndarray) -> np.ndarray:
        """Sponge path ``[T_ctrl, 3]`` (nominal table frame) of parameters ``theta`` in this episode's context
        (:meth:`WipingTask.rollout_path <rdmp_gym.envs.tasks.wiping.task.WipingTask.rollout_path>`)."""
        if self.context is None:
            raise RuntimeError("call reset() before rollout_path()")
        return self.task.rollout_path(theta, self.context)

    def imitation_path(self) -> np.ndarray:
        """The imitation's path ``[T_ctrl, 3]`` in this episode's context (``rollout_path(theta0)`` to round-off;
        :meth:`WipingTask.imitation_path <rdmp_gym.envs.tasks.wiping.task.WipingTask.imitation_path>`)."""
        if self.context is None:
            raise RuntimeError("call reset() before imitation_path()")
        return self.task.imitation_path(self.context)

    def executed_path(self, theta: np.ndarray) -> np.ndarray:
        """The sponge path ``[T_ctrl, 3]`` (nominal table frame) that :meth:`step` executes for parameters
        ``theta``: :meth:`rollout_path`, with :attr:`cup_clearance`'s push where that is on."""
        path = self.rollout_path(theta)
        if (self.cup_clearance is None or not np.all(np.isfinite(path))
                or _workspace_excess(path, self.robot.workspace) > 0):
            return path
        return self._clear_cup(path, self.solve_path(path), {})[0]

    def run_path(self, path: np.ndarray) -> tuple[float, dict]:
        """Simulate a given sponge path ``[T_ctrl, 3]`` (nominal table frame) in this episode's context,
        bypassing the DMP (for tests and hand-made motions). Returns (reward, info)."""
        if self.context is None:
            raise RuntimeError("call reset() before run_path()")
        path = np.asarray(path, dtype=np.float64)
        if path.shape != (self.n_steps, 3):
            raise ValueError(f"path: expected shape ({self.n_steps}, 3), got {path.shape}")
        return self._evaluate(None, path)

    def solve_path(self, path: np.ndarray) -> IKResult:
        """The path IK of a sponge path ``[T, 3]`` (nominal table frame): the joint path the env plans for it."""
        return self.task.solve_path(path)

    def _cup(self) -> Cup | None:
        """The episode's cup as it stands before the wipe (world frame), or None without one."""
        return self.task.cup(self.context)

    def hand_cup_gaps(self, path: np.ndarray) -> dict[str, np.ndarray]:
        """``{part: [T]}``: for each part of the hand (fingers, thumb, palm, sponge), the horizontal gap (m)
        between its points below the cup's top and the cup's side at every control step of ``path [T, 3]``
        (nominal table frame) as planned (inverse kinematics, no simulation); inf where the part is above the
        cup. Empty without a cup."""
        cup = self._cup()
        if cup is None:
            return {}
        hand = self.task.hand_points()
        gaps = hand.gaps(self.solve_path(np.asarray(path, dtype=np.float64)).q, cup)
        return dict(zip(hand.names, gaps.T, strict=True))

    def _clear_cup(self, path: np.ndarray, solution: IKResult, info: dict) -> tuple[np.ndarray, IKResult]:
        """``path [T, 3]`` and its IK solution with :attr:`cup_clearance`'s push (unchanged without a cup);
        records the largest push (m) in ``info["clearance_push"]``."""
        info["clearance_push"] = 0.0
        cup = self._cup()
        if cup is None:
            return path, solution
        path, solution, push = self.cup_clearance.apply(path, solution, self.solve_path, self.task.hand_points(), cup,
                                                        self.scene.control_frame()[1], self.dt)
        info["clearance_push"] = push
        return path, solution

    def smoothness(self, path: np.ndarray, q: np.ndarray) -> Smoothness:
        """Jerk of the commanded path relative to the imitation's in this context (v2: per unit of squared speed,
        :meth:`Smoothness.speed_normalised`), and joint accelerations."""
        jerk_sq = Smoothness.jerk_squared(path, self.dt)
        normalised = self.task_version.speed_normalised_jerk
        measure = Smoothness.speed_normalised if normalised else Smoothness.integrated_jerk
        if self._imitation_jerk is None:
            self._imitation_jerk = measure(self.imitation_path(), self.dt)
        ratio = measure(path, self.dt) / max(self._imitation_jerk, 1e-12)
        return Smoothness(jerk_sq, ratio, Smoothness.peak_accel(q, self.dt))

    def _evaluate(self, theta: np.ndarray | None, path: np.ndarray | None = None) -> tuple[float, dict]:
        info: dict[str, Any] = {"params": None if theta is None else theta.copy()}
        if theta is not None:
            violation = self.action_map.r0_violation(theta)
            if violation > 0:
                return self._invalid(info, "r0", violation - 1.0)
            path = self.rollout_path(theta)
        assert path is not None
        if not np.all(np.isfinite(path)):
            return self._invalid(info, "nonfinite_path", 1.0)
        excess = _workspace_excess(path, self.robot.workspace)
        if excess > 0:
            return self._invalid(info, "workspace", excess / 0.1)
        solution = self.solve_path(path)
        if self.cup_clearance is not None:
            path, solution = self._clear_cup(path, solution, info)
            excess = _workspace_excess(path, self.robot.workspace)
            if excess > 0:
                return self._invalid(info, "workspace", excess / 0.1)
        flat = path[:, 2] <= self._engage
        bad = (solution.pos_error > self.ik_tolerance[0]) | (flat & (solution.rot_error > self.ik_tolerance[1]))
        if np.any(bad):
            severity = 0.5 * np.mean(bad) + 0.5 * min(1.0, float(solution.pos_error.max()) / 0.1)
            return self._invalid(info, "unreachable", severity)
        speed = float(np.max(np.abs(np.diff(solution.q, axis=0)))) / self.dt
        if speed > self.max_joint_speed:
            return self._invalid(info, "joint_speed", speed / self.max_joint_speed - 1.0)

        smooth = self.smoothness(path, solution.q)
        normal = self.scene.control_frame()[1][:, 2]
        plan = JointTargetPlan(solution, self.dt, self._lead, self.scene.joint_lower, self.scene.joint_upper, normal)
        self.scene.set_arm_state(solution.q[0])
        adaptation = self.force_adaptation()
        dirt = DirtField(self.dirt_cells, self.scene.table_frame(actual=True)[1][:, 2], wear_rate=self.wear_rate,
                         contact_threshold=self.reward_settings.contact_threshold)
        callback = self._capture if self.record_frames or self._viewer is not None else None
        self.dirt_left = np.ones(len(self.dirt_cells))
        if callback is not None:
            self.frames.append(self._frame())
        trace = simulate_wipe(self.scene, plan, path[:, 2], adaptation, dirt, self.frame_skip,
                              self.simulation_settings, callback=callback)
        self.dirt_left = trace.dirt
        judged = self.task.evaluate(self._executed(path, solution, trace, smooth), self.context, {})
        valid, reason = judged.info.pop("valid"), judged.info.pop("invalid_reason")
        if not valid:
            logger.debug("penetration %.4f m beyond the limit %.4f m", trace.penetration, self.penetration_limit)
        info.update(judged.info)
        return self._finish(info, judged.terms, judged.cost_trace, valid=valid, reason=reason, unstable=trace.unstable)

    def _executed(self, path: np.ndarray, solution: IKResult, trace: WipeTrace, smooth: Smoothness) -> ToolPath:
        """What the task judges of an executed episode: the commanded path and joints, the hook's record."""
        return ToolPath(TaskPlan(path, *self.scene.control_frame()), solution.q, np.zeros((0, 0)), np.zeros((0, 0)),
                        np.zeros((0, 0)), trace.sponge_pos, trace.steps, trace.unstable, self.dt, self.frame_skip,
                        smooth.jerk_ratio, float(smooth.joint_accel.max()), self.robot.max_joint_accel,
                        WipeRecord(trace, smooth, self.penetration_limit))

    def statistics(self, trace: WipeTrace, smooth: Smoothness) -> dict[str, Any]:
        """The episode's statistics (:mod:`rdmp_gym.envs.tasks.wiping.info`) from its trace and the smoothness of its
        path (:meth:`WipingTask.statistics <rdmp_gym.envs.tasks.wiping.task.WipingTask.statistics>`)."""
        return self.task.statistics(trace, smooth)

    def _invalid(self, info: dict, reason: str, severity: float) -> tuple[float, dict]:
        traces: dict[str, np.ndarray] = {}
        info["cost_terms"] = traces
        terms, cost = invalid_reward(severity, self.n_steps, self.reward_weights, traces)
        info.update(void_statistics(self.n_steps))
        logger.debug("invalid parameters (%s, severity %.3g)", reason, severity)
        return self._finish(info, terms, cost, valid=False, reason=reason, unstable=False)

    def _finish(self, info: dict, terms: dict[str, float], cost: np.ndarray, valid: bool, reason: str,
                unstable: bool) -> tuple[float, dict]:
        reward = sum(terms.values())
        success, causes = outcome(info, valid, unstable, self.success_joint_accel, self.task_version.max_jerk_ratio)
        info.update({"reward_terms": terms, "cost_trace": cost, "valid": valid, "invalid_reason": reason,
                     "unstable": unstable, "is_success": success, "failure_causes": causes,
                     "n_cells": len(self.dirt_cells)})
        return float(reward), info

    # ------------------------------------------------------------------ helpers
    def _observation(self) -> np.ndarray:
        assert self.context is not None
        return self.context.vector().astype(np.float32)

    def _frame(self, dirt: np.ndarray | None = None) -> np.ndarray:
        if self._renderer is None:
            self._renderer = SceneRenderer(self.scene, *self._render_args)
        _, rot = self.scene.table_frame(actual=True)
        return self._renderer.render(self.dirt_cells, self.dirt_left if dirt is None else dirt,
                                     0.5 * self.cell_size, rot)

    def _capture(self, k: int, dirt_left: Callable[[], np.ndarray]) -> None:
        if self._viewer is not None:
            self._viewer.sync()
        if self.record_frames and (k + 1) % self.frame_stride == 0:
            self.frames.append(self._frame(dirt_left()))


def deprecated_v0(**kwargs: Any) -> ArmarWipeEnv:
    """Entry point of the deprecated ``rdmp_gym/ArmarWipe-v0``: warns and makes v1 without the obstacle.

    v0's reward counted dirt beyond the table edge, touching as wiping and let the arm pass through the
    robot; v1 (:class:`ArmarWipeEnv`) fixes all of it and changes the reward's meaning, hence the new version.
    """
    warnings.warn("rdmp_gym/ArmarWipe-v0 is deprecated and will be removed: its reward could be gamed. It now "
                  "makes rdmp_gym/ArmarWipe-v1 with obstacle=False; use rdmp_gym/ArmarWipe-v3, the current task.",
                  DeprecationWarning, stacklevel=2)
    kwargs.setdefault("obstacle", False)
    kwargs.setdefault("version", 1)
    return ArmarWipeEnv(**kwargs)
