"""The episodic face of every rhythmic task on every robot: one ``step`` is one whole DMP rollout in MuJoCo.

``rdmp_gym/{Robot}{Task}-v{N}`` (e.g. ``rdmp_gym/ArmarDrum-v1``, ``rdmp_gym/PandaDrum-v1``) makes a
:class:`RhythmicTaskEnv` of a task description (:mod:`rdmp_gym.envs.tasks`) and a robot description
(:mod:`rdmp_gym.envs.robots`). One ``step``:

1. the action ``a in [-1, 1]^n`` becomes DMP parameters ``theta = theta_imitation + scale * a`` (the task's groups,
   :mod:`rdmp_gym.envs.action`) and the task's own values (its ``extras``, ``scale * a`` each); ``a = 0`` is the
   imitation of the task's demonstration;
2. the task plans the tool path in this episode's context (:meth:`TaskDescription.plan`);
3. the path is checked: finite, inside the robot's reach, solvable by the inverse kinematics with the tool's axis
   along the task frame's, joint speeds within the robot's; an invalid path returns a graded penalty at once
   (``info["valid"] = False``);
4. the simulation core (:class:`~rdmp_gym.envs.servo.ServoSimulation`) executes the joint path with the servos'
   velocity feed-forward, recording every sensor at every physics step;
5. the task judges the record (:meth:`TaskDescription.evaluate`): the reward terms (``info["reward_terms"]``), the
   per-control-step cost (``info["cost_trace"]``, summing to ``-reward``), ``info["is_success"]``,
   ``info["failure_causes"]`` and the task's own info keys.

Rendering: ``render_mode="rgb_array"``; :meth:`RhythmicTaskEnv.record_episode` writes a video of one episode.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from pathlib import Path
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np

from .action import ActionMap, checked_action
from .controller import JointTargetPlan
from .ik import IKResult
from .recording import SceneRenderer, write_video
from .robots import RobotDescription, get_robot
from .servo import ServoSimulation
from .smoothness import Smoothness
from .task_scene import TaskScene
from .tasks import get_task
from .tasks.description import TaskDescription, TaskPlan, ToolPath

__all__ = ["RhythmicTaskEnv"]

logger = logging.getLogger(__name__)

#: IK residuals (position m, angle rad) beyond which a path is unreachable
_IK_TOLERANCE = (0.01, 0.1)
#: IK iterations on the whole path after the coarse pass (12: the joint accelerations have converged)
_IK_FINE_ITERATIONS = 12


class RhythmicTaskEnv(gym.Env):
    """Episodic rhythmic task on a robot; see the module docstring.

    Args:
        task: a registered task name (``"drum"``) or a :class:`~rdmp_gym.envs.tasks.description.TaskDescription`.
        robot: a registered robot name (``"armar3"``, ``"panda"``) or a ``RobotDescription``.
        version: the task's version (one of its ``versions``; ``gym.make`` of an id sets it).
        render_mode: ``None`` or ``"rgb_array"``; width, height, camera: of the rendered frames.
        frame_stride: :meth:`record_episode` keeps a frame every this many control steps.
        **task_settings: keywords of the task's description (e.g. the drumming task's ``tolerance``).
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["rgb_array"], "render_fps": 25}

    def __init__(self, task: str | TaskDescription = "drum", robot: str | RobotDescription = "armar3",
                 version: int = 1, render_mode: str | None = None, width: int = 480, height: int = 360,
                 camera: str = "front", frame_stride: int = 4, **task_settings: Any):
        super().__init__()
        self.task: TaskDescription = get_task(task, **task_settings)
        if self.task.own_faces is not None:
            raise ValueError(f"task: {self.task.name!r} runs on its own envs ({self.task.own_faces}), not on the "
                             f"rhythmic face")
        self.robot: RobotDescription = get_robot(robot)
        if version not in self.task.versions:
            raise ValueError(f"version: the task {self.task.name!r} has the versions {list(self.task.versions)}, "
                             f"got {version!r}")
        self.version = version
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode: expected None or 'rgb_array', got {render_mode!r}")
        self.render_mode = render_mode
        self.scene = TaskScene(self.robot, self.task)
        self.dmp = self.task.imitation()
        self._set_timing()
        self.action_map = ActionMap(self.dmp, self.task.groups, self.task.scales)
        self.extra_scales = np.array(list(self.task.extras.values()), dtype=np.float64)
        size = self.action_map.size + len(self.extra_scales)
        self.action_space = gym.spaces.Box(-1.0, 1.0, shape=(size,), dtype=np.float32)
        low, high = self.task.context_bounds()
        self.observation_space = gym.spaces.Box(low.astype(np.float32), high.astype(np.float32), dtype=np.float32)
        self.ik = self.scene.path_ik()
        self._lead = self.scene.servo_lead()
        self.workspace = self.task.workspace(self.robot)
        self.frame_stride = int(frame_stride)
        self.metadata = {**self.metadata, "render_fps": max(1, round(self.control_rate / self.frame_stride))}
        self._renderer = SceneRenderer(self.scene, width, height, camera) if render_mode else None
        self._render_args = (width, height, camera)
        self.frames: list[np.ndarray] = []
        self.record_frames = False
        self.context: Any = None
        #: the imitation's plan in this episode's context (set by ``reset``)
        self.imitation_plan: TaskPlan | None = None
        self._imitation_jerk: float | None = None

    def _set_timing(self) -> None:
        model = self.scene.model
        self.frame_skip = max(1, round(1.0 / (self.task.control_rate * model.opt.timestep)))
        self.dt = self.frame_skip * model.opt.timestep
        self.control_rate = 1.0 / self.dt
        self.n_steps = max(2, round(self.task.duration / self.dt))
        self.times = np.arange(self.n_steps) * self.dt

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
        """How active each action dimension's parameter is at each control step, ``[T, n]`` in [0, 1] (the task's
        own dimensions act throughout)."""
        weights = self.dmp.param_time_weights(self.times, groups=self.task.groups, transient=0,
                                              stop_at=self._nominal_stop())[:, self.action_map.free]
        return np.c_[weights, np.ones((self.n_steps, len(self.extra_scales)))]

    def _nominal_stop(self) -> float | None:
        return None if self.dmp.ending is None else self.task.duration - 2.0 * self.dmp.period - 1.0

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
        start = self.solve_plan(self.imitation_plan, self.imitation_plan.world()[:1])
        self.scene.set_arm_state(start.q[0])
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
        """The current state as an RGB frame ``[height, width, 3]`` uint8."""
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode='rgb_array' to the env")
            return None
        return self._frame()

    def close(self) -> None:
        """Release the renderer (safe to call more than once)."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def record_episode(self, action: np.ndarray, path: str | Path, fps: float | None = None
                       ) -> tuple[np.ndarray, float, bool, bool, dict]:
        """``step(action)`` while capturing frames every ``frame_stride`` control steps, then write them to a video
        at ``path`` (``.mp4`` or ``.gif``). Returns the step's result."""
        self.record_frames = True
        try:
            result = self.step(action)
        finally:
            self.record_frames = False
        write_video(self.frames, path, fps=self.metadata["render_fps"] if fps is None else fps)
        return result

    # ------------------------------------------------------------------ episode
    def plan(self, theta: np.ndarray, extras: np.ndarray) -> TaskPlan:
        """The task's plan of parameters ``theta [P]`` and its own values ``extras [E]`` in this episode's context."""
        if self.context is None:
            raise RuntimeError("call reset() before plan()")
        return self.task.plan(self.dmp, np.asarray(theta, dtype=np.float64), np.asarray(extras, dtype=np.float64),
                              self.context, self.times, self.scene.table_origin)

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
        return self._execute(given, {"params": None, "extras": None})

    def solve_plan(self, plan: TaskPlan, world: np.ndarray) -> IKResult:
        """The joint path of ``world [T, 3]``, the tool's axis along the task frame's z (converged: a rhythmic
        path's joint accelerations are what the success criteria judge)."""
        return self.ik.solve(world, plan.rotation[:, 2], fine_iterations=_IK_FINE_ITERATIONS, coarse_iterations=150)

    def _evaluate(self, theta: np.ndarray, extras: np.ndarray) -> tuple[float, dict]:
        return self._execute(self.plan(theta, extras), {"params": theta.copy(), "extras": extras.copy()})

    def _execute(self, plan: TaskPlan, info: dict[str, Any]) -> tuple[float, dict]:
        """Check, simulate and judge a plan (see the module docstring, steps 3 to 5)."""
        if not np.all(np.isfinite(plan.path)):
            return self._invalid(info, "nonfinite_path", 1.0)
        world = plan.world()
        local = (world - self.scene.table_origin) @ self.scene.table_rotation
        low, high = self.workspace
        excess = float(np.max(np.maximum(low - local, 0.0) + np.maximum(local - high, 0.0)))
        if excess > 0:
            return self._invalid(info, "workspace", excess / 0.1)
        solution = self.solve_plan(plan, world)
        bad = (solution.pos_error > _IK_TOLERANCE[0]) | (solution.rot_error > _IK_TOLERANCE[1])
        if np.any(bad):
            severity = 0.5 * np.mean(bad) + 0.5 * min(1.0, float(solution.pos_error.max()) / 0.1)
            return self._invalid(info, "unreachable", severity)
        speed = float(np.max(np.abs(np.diff(solution.q, axis=0)))) / self.dt
        if speed > self.robot.max_joint_speed:
            return self._invalid(info, "joint_speed", speed / self.robot.max_joint_speed - 1.0)
        executed = self._simulate(solution)
        path = ToolPath(plan, solution.q, executed.sensors, executed.qpos, executed.qvel, executed.tip, executed.steps,
                        executed.unstable, self.dt, self.frame_skip, self.jerk_ratio(plan.path),
                        float(Smoothness.peak_accel(solution.q, self.dt).max()), self.robot.max_joint_accel)
        outcome = self.task.evaluate(path, self.context, self.scene.sensor)
        causes = ("unstable",) if executed.unstable else outcome.causes
        info.update(outcome.info)
        return self._finish(info, outcome.terms, outcome.cost_trace, True, "", executed.unstable, causes)

    def _simulate(self, solution: IKResult) -> ServoSimulation:
        plan = JointTargetPlan(solution, self.dt, self._lead, self.scene.joint_lower, self.scene.joint_upper)
        self.scene.set_arm_state(solution.q[0])
        simulation = ServoSimulation(self.scene, self.n_steps, self.frame_skip)
        callback = self._capture if self.record_frames else None
        if callback is not None:
            self.frames.append(self._frame())
        simulation.run(plan.q, callback)
        return simulation

    def jerk_ratio(self, path: np.ndarray) -> float:
        """Integrated squared jerk of ``path [T, 3]`` over the imitation's in this context."""
        if self._imitation_jerk is None:
            self._imitation_jerk = Smoothness.integrated_jerk(self.imitation_plan.path, self.dt)
        return Smoothness.integrated_jerk(path, self.dt) / max(self._imitation_jerk, 1e-12)

    def _invalid(self, info: dict, reason: str, severity: float) -> tuple[float, dict]:
        """A graded penalty for a plan that is not executed (``8 + 4 min(severity, 5)``, spread evenly)."""
        cost = np.full(self.n_steps, (8.0 + 4.0 * min(float(severity), 5.0)) / self.n_steps)
        logger.debug("invalid parameters (%s, severity %.3g)", reason, severity)
        return self._finish(info, {"invalid": -float(cost.sum())}, cost, False, reason, False, ("invalid",))

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
        return self._renderer.render()

    def _capture(self, k: int) -> None:
        if (k + 1) % self.frame_stride == 0:
            self.frames.append(self._frame())

