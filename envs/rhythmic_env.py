"""The episodic face of every rhythmic task on every robot: one ``step`` is one whole DMP rollout in MuJoCo.

``rdmp_gym/{Robot}{Task}-v{N}`` (e.g. ``rdmp_gym/ArmarDrum-v1``, ``rdmp_gym/PandaDrum-v1``) makes a
:class:`RhythmicTaskEnv` of a task description (:mod:`rdmp_gym.envs.tasks`) and a robot description
(:mod:`rdmp_gym.envs.robots`). One ``step``:

1. the action ``a in [-1, 1]^n`` becomes DMP parameters ``theta = theta_imitation + scale * a`` (the task's groups,
   :mod:`rdmp_gym.envs.action`) and the task's own values (its ``extras``, ``scale * a`` each); ``a = 0`` is the
   imitation of the task's demonstration;
2. the task plans the tool path in this episode's context (:meth:`TaskDescription.plan`);
3. the task checks the path and solves its joints (:meth:`TaskDescription.solve`; by default: finite, inside the
   robot's reach, solvable by the inverse kinematics with the tool's axis along the task frame's, joint speeds within
   the robot's); a refused path returns the task's graded penalty at once (:meth:`TaskDescription.invalid`,
   ``info["valid"] = False``);
4. the simulation core (:class:`~rdmp_gym.envs.servo.ServoSimulation`) executes the joint path with the servos'
   velocity feed-forward and the task's hook (:meth:`TaskDescription.simulate`; by default the core's own record of
   every sensor at every physics step);
5. the task judges the record (:meth:`TaskDescription.evaluate`): the reward terms (``info["reward_terms"]``), the
   per-control-step cost (``info["cost_trace"]``, summing to ``-reward``), ``info["is_success"]``,
   ``info["failure_causes"]`` and the task's own info keys.

What the tools (learners, evaluation, logs, figures) may know of the task, the face declares from the task's
description: :meth:`RhythmicTaskEnv.task_contract` (its metrics, context fields and kinds, success, smoothness
measure) and :meth:`RhythmicTaskEnv.executed_path`. The task's own attributes and methods are its description's,
``env.unwrapped.task.<name>`` (e.g. ``env.unwrapped.task.tolerance``), for code that knows the task; the face forwards
none of them.

Rendering: ``render_mode="rgb_array"`` (frames with the task's overlay, :meth:`TaskDescription.render_overlay`),
``"depth_array"`` (depth in m) or ``"human"`` (MuJoCo's viewer, following every control step; needs a display);
:meth:`RhythmicTaskEnv.record_episode` writes a video of one episode.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np

from rdmp_gym import RhythmicDMP

from .action import checked_action
from .contract import TaskContract
from .controller import JointTargetPlan
from .ik import IKResult
from .recording import SceneRenderer, write_video
from .robots import RobotDescription, get_robot
from .smoothness import Smoothness
from .task_scene import standard_stage
from .tasks import TASKS, get_task
from .tasks.description import Rejection, Solution, TaskDescription, TaskPlan, ToolPath
from .viewer import HumanViewer

__all__ = ["RhythmicTaskEnv"]

logger = logging.getLogger(__name__)

#: IK iterations on the whole path after the coarse pass (12: the joint accelerations have converged)
_IK_FINE_ITERATIONS = 12


class RhythmicTaskEnv(gym.Env):
    """Episodic rhythmic task on a robot; see the module docstring.

    Args:
        task: a registered task name (:data:`~rdmp_gym.envs.tasks.TASKS`, e.g. ``"drum"``) or a
            :class:`~rdmp_gym.envs.tasks.description.TaskDescription`.
        robot: a registered robot name (``"armar3"``, ``"panda"``) or a ``RobotDescription``.
        version: the task's version (one of its ``versions``; ``gym.make`` of an id sets it); None: its latest.
        render_mode: ``None``, ``"rgb_array"``, ``"depth_array"`` or ``"human"``; width, height (default the
            task's :attr:`~rdmp_gym.envs.tasks.description.TaskDescription.frame_size`), camera: of the rendered
            frames.
        record_frames: capture frames during every step into :attr:`frames`; frame_stride: every how many control
            steps (also :meth:`record_episode`'s).
        **task_settings: keywords of the task's description (e.g. the drumming task's ``tolerance``).

    The face holds the task's description as :attr:`task`: the task's own attributes and methods are
    ``env.unwrapped.task.<name>``; the face's attributes are only its own (the episode, the stage, the action layout).
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["human", "rgb_array", "depth_array"], "render_fps": 25}

    def __init__(self, task: str | TaskDescription = "drum", robot: str | RobotDescription = "armar3",
                 version: int | None = None, render_mode: str | None = None, width: int | None = None,
                 height: int | None = None, camera: str | None = "front", frame_stride: int = 4,
                 record_frames: bool = False, **task_settings: Any):
        super().__init__()
        if isinstance(task, str) and task in TASKS:
            version = max(TASKS[task].versions) if version is None else version
            task_settings = {**TASKS[task].face_settings(robot, version), **task_settings}
        self.task: TaskDescription = get_task(task, **task_settings)
        version = max(self.task.versions) if version is None else version
        self.robot: RobotDescription = get_robot(robot)
        if version not in self.task.versions:
            raise ValueError(f"version: the task {self.task.name!r} has the versions {list(self.task.versions)}, "
                             f"got {version!r}")
        self.version = version
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise ValueError(f"render_mode: expected None or one of {self.metadata['render_modes']}, "
                             f"got {render_mode!r}")
        self.render_mode = render_mode
        self.dmp = self.task.imitation()
        stage = self.task.stage(self.robot) or standard_stage(self.task, self.robot)
        self.scene = stage.scene
        self.frame_skip, self.dt, self.n_steps, self.times = stage.frame_skip, stage.dt, stage.n_steps, stage.times
        self.control_rate = 1.0 / self.dt
        self.action_map = stage.action_map
        self.extra_scales = np.array(list(self.task.extras.values()), dtype=np.float64)
        size = self.action_map.size + len(self.extra_scales)
        self.action_space = gym.spaces.Box(-1.0, 1.0, shape=(size,), dtype=np.float32)
        low, high = self.task.context_bounds()
        self.observation_space = gym.spaces.Box(low.astype(np.float32), high.astype(np.float32), dtype=np.float32)
        self.ik = stage.ik
        #: the servos' velocity feed-forward gains ``[n]`` (s)
        self.servo_lead = self.scene.servo_lead()
        self.workspace = self.task.workspace(self.robot)
        self.frame_stride = int(frame_stride)
        self.metadata = {**self.metadata, "render_fps": max(1, round(self.control_rate / self.frame_stride))}
        default_width, default_height = self.task.frame_size
        self._render_args = (default_width if width is None else width, default_height if height is None else height,
                             camera)
        self._renderer: SceneRenderer | None = None
        self._viewer = HumanViewer(self.scene) if render_mode == "human" else None
        if render_mode in ("rgb_array", "depth_array") or record_frames:
            self._renderer = SceneRenderer(self.scene, *self._render_args)
        self.frames: list[np.ndarray] = []
        self.record_frames = bool(record_frames)
        #: the episode's context (set by ``reset``)
        self.context: Any = None
        #: what the task draws on this episode's frames (its record of the episode so far; None before the first step)
        self.overlay: Any = None
        #: the imitation's plan in this episode's context (set by ``reset``)
        self.imitation_plan: TaskPlan | None = None
        self._imitation_jerk: float | None = None
        #: the solution the running episode executes and its servo targets (set during ``step``; a cycle-level face
        #: changes both in place from a cycle's start on, :mod:`rdmp_gym.envs.cycle_env`)
        self.solution: Solution | None = None
        self.live_targets: JointTargetPlan | None = None
        #: what the last episode executed (None before the first step and after a refused one)
        self.tool_path: ToolPath | None = None
        #: ``listener(k, overlay)`` after every control step ``k`` of an episode (None: no listener)
        self.control_listener: Callable[[int, Any], None] | None = None
        self._built = True

    def __setattr__(self, name: str, value: Any) -> None:
        """Set the face's attribute ``name``; once the face is built, an attribute that only the task has is refused
        (AttributeError naming it and ``env.unwrapped.task``), so that a setting meant for the task is never lost."""
        state = self.__dict__
        if (state.get("_built") and name not in state and not hasattr(type(self), name)
                and hasattr(state["task"], name)):
            raise AttributeError(f"{name}: an attribute of the task, not of the env; set env.unwrapped.task.{name}")
        super().__setattr__(name, value)

    # ------------------------------------------------------------------ action <-> parameters
    def _check_action(self, action: Any) -> np.ndarray:
        return np.clip(checked_action(action, self.action_space.shape), -1.0, 1.0)

    def _split(self, a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(DMP parameters ``[P]``, the task's own values ``[E]``) of a clipped action."""
        n = self.action_map.size
        return self.action_map.to_params(a[:n]), self.extra_scales * a[n:]

    def action_to_params(self, action: np.ndarray) -> np.ndarray:
        """DMP parameters ``theta [P]`` (the task's groups) of an action ``[n]`` (clipped to [-1, 1])."""
        return self._split(self._check_action(action))[0]

    def params_to_action(self, theta: np.ndarray) -> np.ndarray:
        """An action ``[n]`` (float32) that maps to ``theta [P]``, with 0 in the task's own dimensions."""
        return np.r_[self.action_map.to_action(theta), np.zeros(len(self.extra_scales))].astype(np.float32)

    def action_slices(self) -> dict[str, slice]:
        """``{name: slice of the action}``: the DMP's groups, then each of the task's own dimensions."""
        slices = dict(self.action_map.action_slices())
        for index, name in enumerate(self.task.extras):
            slices[name] = slice(self.action_map.size + index, self.action_map.size + index + 1)
        return slices

    def action_time_weights(self) -> np.ndarray:
        """How active each action dimension's parameter is at each control step, ``[T, n]`` in [0, 1]
        (:meth:`TaskDescription.action_time_weights`)."""
        return self.task.action_time_weights(self.dmp, self.times, self.action_map)

    def param_slices(self) -> dict[str, slice]:
        """``{group: slice}`` of the DMP parameters ``theta [P]`` (the task's groups)."""
        return dict(self.dmp.param_slices(self.task.groups))

    def policy_dmp(self, theta: np.ndarray) -> RhythmicDMP:
        """The imitation DMP with the parameters ``theta [P]`` (the task's groups): the DMP a policy executes, as a
        run saves it."""
        return self.dmp.with_params(np.asarray(theta, dtype=np.float64), self.task.groups)

    # ------------------------------------------------------------------ the task's contract
    def task_contract(self) -> TaskContract:
        """What the tools may know of the task (:mod:`rdmp_gym.envs.contract`), from its description: its metrics,
        context fields and kinds, the smoothness measure of the executed path (the tool path, x y z in the task
        frame, at the control period); every episode reports ``is_success``."""
        task = self.task
        return TaskContract(name=task.name, metrics=tuple(task.metrics), context_fields=dict(task.context_fields()),
                            has_success=True, smoothness=task.smoothness_measure, dt=float(self.dt),
                            path_labels=("x", "y", "z"), context_kind=task.context_kind)

    def executed_path(self, action: np.ndarray) -> np.ndarray:
        """The tool path ``[T, 3]`` (task frame) that :meth:`step` executes for ``action [n]`` (clipped to [-1, 1]) in
        this episode's context, as planned and changed by the task before execution
        (:meth:`TaskDescription.execution_path`), without simulating it."""
        plan = self.plan(*self._split(self._check_action(action)))
        return self.task.execution_path(plan, self)

    # ------------------------------------------------------------------ gym API
    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        """Draw a context (``options`` fix its fields; see the task's context) and put the robot at rest at the
        imitation's start."""
        super().reset(seed=seed)
        if options is not None and not isinstance(options, Mapping):
            raise ValueError(f"options: expected a dict, got {type(options).__name__}")
        self.context = self.task.sample_context(self.np_random, options)
        self.task.place(self.scene.model, self.context)
        self.imitation_plan = self.plan(self.action_map.theta0, np.zeros(len(self.extra_scales)))
        self._imitation_jerk = None
        self.overlay = None
        self.scene.set_arm_state(self.task.rest_pose(self.context, self.imitation_plan, self))
        self.frames = []
        return self._observation(), {"context": self.context.vector()}

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict]:
        """Run one whole episode with the parameters of ``action [n]`` (clipped to [-1, 1]; NaN, infinite values or a
        wrong shape raise ValueError). Always ``terminated=True, truncated=False``."""
        if self.context is None:
            raise RuntimeError("call reset() before step()")
        theta, extras = self._split(self._check_action(action))
        self.frames = []
        reward, info = self._evaluate(theta, extras)
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
        """Release the renderer and the viewer (safe to call more than once)."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
        if self._viewer is not None:
            self._viewer.close()

    def record_episode(self, action: np.ndarray, path: str | Path, fps: float | None = None
                       ) -> tuple[np.ndarray, float, bool, bool, dict]:
        """``step(action)`` while capturing frames every ``frame_stride`` control steps, then write them to a video
        at ``path`` (``.mp4`` or ``.gif``). Returns the step's result."""
        recording = self.record_frames
        self.record_frames = True
        try:
            result = self.step(action)
        finally:
            self.record_frames = recording
        write_video(self.frames, path, fps=self.metadata["render_fps"] if fps is None else fps)
        return result

    # ------------------------------------------------------------------ episode
    def plan(self, theta: np.ndarray, extras: np.ndarray) -> TaskPlan:
        """The task's plan of parameters ``theta [P]`` and its own values ``extras [E]`` in this episode's context."""
        if self.context is None:
            raise RuntimeError("call reset() before plan()")
        return self.task.plan(self.dmp, np.asarray(theta, dtype=np.float64), np.asarray(extras, dtype=np.float64),
                              self.context, self.times, self.scene.table_origin)

    def resume_plan(self, theta: np.ndarray, extras: np.ndarray, live: TaskPlan, step: int) -> TaskPlan:
        """The task's plan of ``theta [P]`` and ``extras [E]`` taking over from the running plan ``live`` at control
        step ``step`` (:meth:`~rdmp_gym.envs.tasks.description.TaskDescription.resume_plan`)."""
        if self.context is None:
            raise RuntimeError("call reset() before resume_plan()")
        return self.task.resume_plan(live, int(step), self.dmp, np.asarray(theta, dtype=np.float64),
                                     np.asarray(extras, dtype=np.float64), self.context, self.times,
                                     self.scene.table_origin)

    def rollout_path(self, theta: np.ndarray) -> np.ndarray:
        """The tool path ``[T, 3]`` (task frame) that the task plans for DMP parameters ``theta [P]`` (its own values
        at 0) in this episode's context."""
        return self.plan(theta, np.zeros(len(self.extra_scales))).path

    def action_path(self, action: np.ndarray) -> np.ndarray:
        """The tool path ``[T, 3]`` (task frame) that :meth:`step` plans for ``action [n]`` in this context."""
        return self.plan(*self._split(self._check_action(action))).path

    def run_path(self, path: np.ndarray) -> tuple[float, dict]:
        """Execute a given tool path ``[T, 3]`` (task frame, m) in this episode's context, bypassing the DMP (for
        tests and hand-made motions: standing still, pressing, ...), judged as the task judges ``step``. Returns
        (reward, info)."""
        if self.context is None:
            raise RuntimeError("call reset() before run_path()")
        path = np.asarray(path, dtype=np.float64)
        if path.shape != (self.n_steps, 3):
            raise ValueError(f"path: expected shape ({self.n_steps}, 3), got {path.shape}")
        plan = self.imitation_plan
        given = TaskPlan(path, plan.origin, plan.rotation, plan.extras)
        info: dict[str, Any] = {"params": None}
        if len(self.extra_scales):
            info["extras"] = None
        return self._execute(given, info)

    def solve_plan(self, plan: TaskPlan, world: np.ndarray) -> IKResult:
        """The joint path of ``world [T, 3]``, the tool's axis along the task frame's z (converged: a rhythmic
        path's joint accelerations are what the success criteria judge)."""
        return self.ik.solve(world, plan.rotation[:, 2], fine_iterations=_IK_FINE_ITERATIONS, coarse_iterations=150)

    def _evaluate(self, theta: np.ndarray, extras: np.ndarray) -> tuple[float, dict]:
        info: dict[str, Any] = {"params": theta.copy()}
        if len(self.extra_scales):
            info["extras"] = extras.copy()
        rejection = self.task.check_params(theta)
        if rejection is not None:
            return self._invalid(info, rejection)
        return self._execute(self.plan(theta, extras), info)

    def _execute(self, plan: TaskPlan, info: dict[str, Any]) -> tuple[float, dict]:
        """Check, simulate and judge a plan (see the module docstring, steps 3 to 5)."""
        solution = self.task.solve(plan, self)
        if isinstance(solution, Rejection):
            return self._invalid(info, solution)
        info.update(solution.info)
        listening = self.record_frames or self._viewer is not None or self.control_listener is not None
        capture = self._capture if listening else None
        self.overlay = None
        self.solution = solution
        path = self.task.simulate(solution, self, capture)
        self.tool_path = path
        self.overlay = path.record
        outcome = self.task.evaluate(path, self.context, self.scene.sensor)
        causes = ("unstable",) if path.unstable and outcome.valid else outcome.causes
        info.update(outcome.info)
        return self._finish(info, outcome.terms, outcome.cost_trace, outcome.valid, outcome.reason, path.unstable,
                            causes)

    def joint_targets(self, joints: IKResult, normal: np.ndarray | None = None) -> JointTargetPlan:
        """The servo targets of the joint path ``joints`` (the servos' feed-forward, the joint limits; the pressing
        direction ``normal [3]``, default +z), held as :attr:`live_targets` while the episode runs: a task's
        :meth:`~TaskDescription.simulate` builds its targets here."""
        self.live_targets = JointTargetPlan(joints, self.dt, self.servo_lead, self.scene.joint_lower,
                                            self.scene.joint_upper, normal)
        return self.live_targets

    def jerk_ratio(self, path: np.ndarray) -> float:
        """Integrated squared jerk of ``path [T, 3]`` over the imitation's in this context."""
        if self._imitation_jerk is None:
            self._imitation_jerk = Smoothness.integrated_jerk(self.imitation_plan.path, self.dt)
        return Smoothness.integrated_jerk(path, self.dt) / max(self._imitation_jerk, 1e-12)

    def _invalid(self, info: dict, rejection: Rejection) -> tuple[float, dict]:
        """The task's graded penalty for a plan that is not executed (:meth:`TaskDescription.invalid`)."""
        self.tool_path = None
        info.update(rejection.info)
        outcome = self.task.invalid(rejection.reason, rejection.severity, self.n_steps, self.context)
        info.update(outcome.info)
        logger.debug("invalid parameters (%s, severity %.3g)", rejection.reason, rejection.severity)
        return self._finish(info, outcome.terms, outcome.cost_trace, False, rejection.reason, False, outcome.causes)

    def _finish(self, info: dict, terms: dict[str, float], cost: np.ndarray, valid: bool, reason: str,
                unstable: bool, causes: tuple[str, ...]) -> tuple[float, dict]:
        info.update({"reward_terms": terms, "cost_trace": cost, "valid": valid, "invalid_reason": reason,
                     "unstable": unstable, "is_success": not causes, "failure_causes": causes})
        return float(sum(terms.values())), info

    # ------------------------------------------------------------------ helpers
    def _observation(self) -> np.ndarray:
        return self.context.vector().astype(np.float32)

    def _frame(self) -> np.ndarray:
        if self._renderer is None:
            self._renderer = SceneRenderer(self.scene, *self._render_args)
        return self.task.render_overlay(self._renderer, self.context, self.overlay)

    def _capture(self, k: int, overlay: Any = None) -> None:
        """Before the first control step (``k = -1``) the first frame; after control step ``k`` the viewer's update
        and every ``frame_stride`` steps a frame (with the task's ``overlay`` of the episode so far, where given)."""
        if overlay is not None:
            self.overlay = overlay
        if k < 0:
            if self.record_frames or self._viewer is not None:
                self.frames.append(self._frame())
            return
        if self.control_listener is not None:
            self.control_listener(k, overlay)
        if self._viewer is not None:
            self._viewer.sync()
        if self.record_frames and (k + 1) % self.frame_stride == 0:
            self.frames.append(self._frame())

