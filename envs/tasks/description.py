"""What an env knows of a task: one :class:`TaskDescription` per task, as a robot is one description.

A task description holds everything task-specific, so that one episodic face
(:class:`~rdmp_gym.envs.rhythmic_env.RhythmicTaskEnv`) and one step twin
(:class:`~rdmp_gym.envs.rhythmic_step.RhythmicTaskStepEnv`) serve every robot x task on one simulation core
(:class:`~rdmp_gym.envs.servo.ServoSimulation`):

- the **objects** it adds to the room (:meth:`compose`: its tool on the robot's mount, its objects, its sensors;
  :attr:`room`: the room its scene starts from, where its fixed objects come before the robot);
- the **context** (:meth:`context_bounds`, :meth:`sample_context`, :meth:`place`): what ``reset`` draws, checks and
  observes, and how the objects move for it;
- the **imitation** (:meth:`imitation`): the DMP fitted to the task's demonstration, and the **action layout**
  (:attr:`groups`, :attr:`scales`, :attr:`extras`: DMP parameter groups and the task's own action dimensions);
- the **plan** (:meth:`plan`): the tool path of parameters in a context (the DMP rolled out as the task runs it);
- the **bookkeeping, reward and success** (:meth:`evaluate`): from the simulation's record, the reward terms, the
  per-control-step cost trace, the info keys, ``is_success`` and the failure causes;
- the **execution** on the faces, each hook with a default that is the faces' own way: what the faces run the task
  on (:meth:`stage`: scene, timing, action layout, inverse kinematics), where the robot rests at ``reset``
  (:meth:`rest_pose`), the parameters the task refuses before planning (:meth:`check_params`), the inverse kinematics
  and path checks (:meth:`solve`: the joint plan, or a rejection with its reason and severity), the simulation with
  the task's hook on the core (:meth:`simulate`), the penalty of a rejected path (:meth:`invalid`) and the rendered
  frame with the task's overlay (:meth:`render_overlay`);
- the **step interface** on the step twin (:meth:`step_book`): a :class:`~rdmp_gym.envs.step_book.StepBook` with the
  plan the twin shifts, the simulation, the shifted target, the per-step bookkeeping, an early end, the step's reward
  and info, the observation and the settings the twin refuses; by default the generic book (the tool tip observed, a
  reward judged every few control steps);
- the **learner defaults** (:attr:`learner_defaults`): settings a learner may read from the task, by agent name;
- the **declaration** the tools read (:class:`~rdmp_gym.envs.contract.TaskContract`, built by the episodic face):
  the task's per-episode :attr:`metrics` (info keys), its :meth:`context_fields` and, where it sorts its contexts
  into kinds, :attr:`context_kind`, the :attr:`smoothness_measure` of an executed path and the path an episode
  executes (:meth:`execution_path`).

Adding a task is one folder with its description and one line in :data:`rdmp_gym.envs.tasks.TASKS` (or a call of
:func:`rdmp_gym.envs.tasks.register_task` from user code); the registry builds a description with :meth:`build` (a
task whose versions have descriptions of their own picks the version's there).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from ..contract import Metric

if TYPE_CHECKING:          # the registry imports this module without MuJoCo (string entry points)
    import mujoco

    from rdmp_gym import RhythmicDMP

    from ..action import ActionMap
    from ..ik import IKResult, PathIK
    from ..recording import SceneRenderer
    from ..robots import RobotDescription

__all__ = ["Outcome", "Rejection", "Solution", "Stage", "TaskDescription", "TaskPlan", "ToolPath"]


@dataclass(frozen=True)
class TaskPlan:
    """The tool path of one episode as the task plans it.

    Attributes:
        path: tool-tip positions ``[T, 3]`` in the task frame, one per control step.
        origin, rotation: the task frame in the world (``[3]``, ``[3, 3]``); the tool's axis is held along the
            frame's z axis (column 2 of ``rotation``), pointing into -z.
        extras: what the task's :meth:`TaskDescription.evaluate` needs of the plan (e.g. beat times).
    """

    path: np.ndarray
    origin: np.ndarray
    rotation: np.ndarray
    extras: Mapping[str, Any] = field(default_factory=dict)

    def world(self) -> np.ndarray:
        """The path in the world frame ``[T, 3]``."""
        return self.path @ self.rotation.T + self.origin


@dataclass(frozen=True)
class ToolPath:
    """What the simulation executed, for :meth:`TaskDescription.evaluate`.

    Attributes:
        plan: the planned path.
        q: the planned joint path ``[T, n]``.
        sensors: MuJoCo's sensordata at every physics step ``[T * frame_skip, S]``.
        qpos, qvel: the state after every control step ``[T, nq]``, ``[T, nv]``.
        tip: the tool tip's world position after every control step ``[T, 3]``.
        steps: control steps simulated (``T`` unless the simulation diverged).
        unstable: the simulation diverged (NaN or MuJoCo's reset).
        dt, frame_skip: control period (s) and physics steps per control step.
        jerk_ratio: integrated squared jerk of the planned path over the imitation's in the same context.
        peak_joint_accel: largest planned joint acceleration (rad/s²).
        max_joint_accel: the robot's joint acceleration limit (rad/s²).
        record: what the task's hook on the simulation core recorded (None without a hook).
    """

    plan: TaskPlan
    q: np.ndarray
    sensors: np.ndarray
    qpos: np.ndarray
    qvel: np.ndarray
    tip: np.ndarray
    steps: int
    unstable: bool
    dt: float
    frame_skip: int
    jerk_ratio: float
    peak_joint_accel: float
    max_joint_accel: float
    record: Any = None


@dataclass
class Outcome:
    """A task's judgement of one episode.

    Attributes:
        terms: reward terms ``{name: value}`` (their sum is the reward).
        cost_trace: per-control-step cost ``[T]`` (sums to minus the reward).
        info: the task's info keys.
        causes: the success criteria missed (empty for a success).
        valid: whether the episode counts (False: void, e.g. the task's limits broken during the simulation).
        reason: why it is void (``info["invalid_reason"]``; empty where valid).
    """

    terms: dict[str, float]
    cost_trace: np.ndarray
    info: dict[str, Any]
    causes: tuple[str, ...]
    valid: bool = True
    reason: str = ""


@dataclass(frozen=True)
class Stage:
    """What the faces run a task on (:meth:`TaskDescription.stage`).

    Attributes:
        scene: the scene (``model``, ``data``, the arm's actuators and joint limits, the tool's ``tip_site``, the
            nominal ``table_origin``, ``sensor`` names, ``set_arm_state``, ``servo_lead``).
        frame_skip, dt: physics steps per control step, control period (s).
        n_steps, times: control steps of an episode and their times ``[T]`` (s).
        action_map: the DMP parameters in the action (:class:`~rdmp_gym.envs.action.ActionMap`).
        ik: the path inverse kinematics of the tool (:class:`~rdmp_gym.envs.ik.PathIK`).
    """

    scene: Any
    frame_skip: int
    dt: float
    n_steps: int
    times: np.ndarray
    action_map: ActionMap
    ik: PathIK


@dataclass(frozen=True)
class Solution:
    """A path the task accepts (:meth:`TaskDescription.solve`): the ``plan`` to execute (as planned, or as the task
    changed it), its joint path ``joints`` and the info keys of the check."""

    plan: TaskPlan
    joints: IKResult
    info: Mapping[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Rejection:
    """A path the task refuses without simulating it: ``reason`` (``info["invalid_reason"]``), ``severity`` (how
    far it is from acceptable, >= 0; the penalty grows with it) and the info keys of the check."""

    reason: str
    severity: float
    info: Mapping[str, Any] = field(default_factory=dict)


class TaskDescription(ABC):
    """One rhythmic task; see the module docstring. Subclasses set the class attributes and the methods."""

    #: the task's part of an env id (``rdmp_gym/{Robot}{name}-v{version}``)
    name: ClassVar[str]
    #: the task's versions with their episodic and step ids
    versions: ClassVar[tuple[int, ...]] = (1,)
    #: the DMP parameter groups in the action, and their action scales (see :mod:`rdmp_gym.envs.action`)
    groups: tuple[str, ...] = ("periodic", "transient", "amplitude")
    scales: Mapping[str, float] = {}
    #: the task's own action dimensions, after the DMP's: name -> scale (the value at ``a = +1``)
    extras: Mapping[str, float] = {}
    #: the site of the task's tool that the inverse kinematics places on the path (without the tool prefix)
    tool_site: str = "tip"
    #: the MJCF of the room the task's scene starts from (None: the standard room: floor, light, cameras, table; a
    #: task with fixed objects of its own names a room that holds them, so that they come before the robot)
    room: ClassVar[str | Path | None] = None
    #: episode length (s) and control rate (Hz)
    duration: float = 8.0
    control_rate: float = 100.0
    #: settings a learner may read from the task: ``{agent: {option: value}}``
    learner_defaults: Mapping[str, Mapping[str, Any]] = {}
    #: the rendered frames' default size (width, height) in pixels
    frame_size: ClassVar[tuple[int, int]] = (480, 360)
    #: the task's per-episode metrics (each read from ``info`` under its key), in the order tables show them; the
    #: return is every task's and is not listed
    metrics: ClassVar[tuple[Metric, ...]] = ()
    #: how the smoothness of an executed path is measured: ``"jerk"`` (integrated squared jerk) or
    #: ``"speed_normalised_jerk"`` (per unit of integrated squared speed)
    smoothness_measure: str = "jerk"
    #: ``context_kind(observation [C]) -> str``: the kind of a context, where the task sorts its contexts into kinds
    #: (validation contexts spread over them); None (the default) where it does not
    context_kind: Callable[[np.ndarray], str] | None = None

    @classmethod
    def build(cls, **settings: Any) -> TaskDescription:
        """The description of ``settings`` (default: ``cls(**settings)``; a task whose versions have descriptions of
        their own returns the settings' version's)."""
        return cls(**settings)

    @classmethod
    def defaults_for(cls, version: int) -> Mapping[str, Mapping[str, Any]]:
        """The learner defaults of the task's ``version`` (default: :attr:`learner_defaults` for every version)."""
        return cls.learner_defaults

    @classmethod
    def face_settings(cls, robot: str | RobotDescription, version: int) -> dict[str, Any]:
        """The settings a face adds to the task's own when it builds the task by name for ``robot`` at ``version``
        (default: none; a task whose description depends on the robot or the version takes them here)."""
        return {}

    @classmethod
    def typed_settings(cls, settings: Mapping[str, Any]) -> Any:
        """The settings of an env of the task (the face's keywords but ``task``) as the task's typed record, checked
        without building the task, or None where the task has none (default: its keywords are checked by building
        the description)."""
        return None

    @abstractmethod
    def compose(self, spec: mujoco.MjSpec, robot: RobotDescription, robot_prefix: str, tool_prefix: str) -> None:
        """Add the task to the room ``spec`` (the robot already attached with ``robot_prefix``): its tool on the
        robot's tool mount (names prefixed ``tool_prefix``), its objects and its sensors."""

    @abstractmethod
    def imitation(self) -> RhythmicDMP:
        """The imitation DMP (fitted to the task's demonstration; the action's zero)."""

    @abstractmethod
    def context_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """``(low [C], high [C])``: the observation's bounds (what ``reset(options=...)`` accepts)."""

    @abstractmethod
    def sample_context(self, rng: np.random.Generator, options: Mapping[str, Any] | None) -> Any:
        """One episode's context (drawn with ``rng``; ``options`` fix fields, checked); it has ``vector() [C]``."""

    @abstractmethod
    def place(self, model: mujoco.MjModel, context: Any) -> None:
        """Move the task's objects in ``model`` for ``context`` (before the data is reset)."""

    @abstractmethod
    def plan(self, dmp: RhythmicDMP, theta: np.ndarray, extras: np.ndarray, context: Any, times: np.ndarray,
             table_origin: np.ndarray) -> TaskPlan:
        """The tool path of parameters ``theta [P]`` (groups :attr:`groups`) and the task's action values
        ``extras [E]`` in ``context``, at the control times ``times [T]``; ``table_origin [3]``: the nominal table
        frame's origin in the world (its axes are the world's)."""

    def resume_plan(self, live: TaskPlan, step: int, dmp: RhythmicDMP, theta: np.ndarray, extras: np.ndarray,
                    context: Any, times: np.ndarray, table_origin: np.ndarray) -> TaskPlan:
        """The plan of ``theta [P]`` and ``extras [E]`` that takes over from the running plan ``live`` at control step
        ``step`` (a cycle's change on the cycle-level face). Default: :meth:`plan`, the new parameters' plan from the
        start, right for a plan that is a function of its parameters alone; a task whose plan has a state of its own
        (the drumming task's rhythm follower) goes on from that state at ``step`` instead."""
        return self.plan(dmp, theta, extras, context, times, table_origin)

    @abstractmethod
    def evaluate(self, path: ToolPath, context: Any, sensor: Mapping[str, slice]) -> Outcome:
        """The reward terms, cost trace, info and failure causes of an executed episode; ``sensor`` maps the
        scene's sensor names to their columns of ``path.sensors``."""

    def context_fields(self) -> Mapping[str, tuple[int, int]]:
        """The observation's named fields ``{name: (start, size)}`` (default: none, the observation is unnamed)."""
        return {}

    def execution_path(self, plan: TaskPlan, face: Any) -> np.ndarray:
        """The tool path ``[T, 3]`` (task frame) an episode executes for ``plan`` on the ``face``, without simulating
        it: what the smoothness is measured on and the figures draw (default: the planned path; a task that changes
        the path before executing it gives the changed one)."""
        return plan.path

    def cue(self, context: Any, times: np.ndarray) -> np.ndarray:
        """What the task signals to the robot at the control times ``times [T]`` (a step-based policy observes it;
        default: nothing, zeros)."""
        return np.zeros(len(times))

    def workspace(self, robot: RobotDescription) -> tuple[np.ndarray, np.ndarray]:
        """The box ``(low [3], high [3])`` of the table frame the tool tip may be commanded in."""
        return robot.workspace

    # ------------------------------------------------------------------ the cycle-level face
    def cycle_starts(self, face: Any) -> np.ndarray:
        """The start times ``[K]`` (s) of the cycles the cycle-level face (:mod:`rdmp_gym.envs.cycle_env`) steps
        through on the episodic ``face`` (default: the DMP's, :func:`rdmp_gym.dmp.cycles.cycle_starts`)."""
        from rdmp_gym.dmp.cycles import cycle_starts

        return cycle_starts(face.dmp, face.n_steps * face.dt)

    def cycle_state_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """``(low [S], high [S])`` of :meth:`cycle_state` (default: the tool's position within 2 m of the task
        frame's origin and its offset from its path within 0.5 m)."""
        return np.r_[np.full(3, -2.0), np.full(3, -0.5)], np.r_[np.full(3, 2.0), np.full(3, 0.5)]

    def cycle_state(self, face: Any, step: int | None, overlay: Any) -> np.ndarray:
        """What the task reports of the episode on the episodic ``face`` when a cycle starts at control step ``step``
        (None: at rest before the first), ``[S]``; ``overlay`` is what the task's :meth:`simulate` gave its last
        capture (None where it gives none). Default: the tool tip's position in the task frame and its offset from
        the path it follows (m)."""
        plan = face.imitation_plan if step is None else face.solution.plan
        tip = face.scene.data.site_xpos[face.scene.tip_site]
        local = (tip - plan.origin) @ plan.rotation
        return np.r_[local, local - plan.path[0 if step is None else step - 1]]

    # ------------------------------------------------------------------ execution on the faces
    def stage(self, robot: RobotDescription) -> Stage | None:
        """What the faces run the task on with ``robot``, or None (the default) for the standard stage
        (:func:`~rdmp_gym.envs.task_scene.standard_stage`: the room composed with the robot and the task, the action
        map of :attr:`groups` and :attr:`scales`, the scene's path inverse kinematics)."""
        return None

    def action_time_weights(self, dmp: RhythmicDMP, times: np.ndarray, action_map: ActionMap) -> np.ndarray:
        """How active each action dimension is at the control times ``times [T]``, ``[T, n]`` in [0, 1] (default: the
        DMP's parameter groups, the stop nominally ``2`` periods ``+ 1`` s before the end, then the task's own
        dimensions acting throughout)."""
        stop = None if dmp.ending is None else self.duration - 2.0 * dmp.period - 1.0
        weights = dmp.param_time_weights(times, groups=self.groups, transient=0, stop_at=stop)[:, action_map.free]
        return np.c_[weights, np.ones((len(times), len(self.extras)))]

    def rest_pose(self, context: Any, plan: TaskPlan, face: Any) -> np.ndarray:
        """The joints ``[n]`` the robot rests at when an episode starts in ``context``; ``plan`` is the imitation's
        (default: the face's inverse kinematics of the plan's first point)."""
        return face.solve_plan(plan, plan.world()[:1]).q[0]

    def check_params(self, theta: np.ndarray) -> Rejection | None:
        """A rejection of DMP parameters ``theta [P]`` before they are planned, or None (default: none)."""
        return None

    def solve(self, plan: TaskPlan, face: Any) -> Solution | Rejection:
        """The joint path of ``plan`` on the ``face`` (its scene, inverse kinematics, robot, control period), or why
        it is refused. Default: the path is finite, inside the robot's reach (:meth:`workspace`), solvable by the
        inverse kinematics with the tool's axis along the task frame's z, joint speeds within the robot's."""
        if not np.all(np.isfinite(plan.path)):
            return Rejection("nonfinite_path", 1.0)
        world = plan.world()
        local = (world - face.scene.table_origin) @ face.scene.table_rotation
        low, high = face.workspace
        excess = float(np.max(np.maximum(low - local, 0.0) + np.maximum(local - high, 0.0)))
        if excess > 0:
            return Rejection("workspace", excess / 0.1)
        solution = face.solve_plan(plan, world)
        bad = (solution.pos_error > _IK_TOLERANCE[0]) | (solution.rot_error > _IK_TOLERANCE[1])
        if np.any(bad):
            severity = 0.5 * np.mean(bad) + 0.5 * min(1.0, float(solution.pos_error.max()) / 0.1)
            return Rejection("unreachable", severity)
        speed = float(np.max(np.abs(np.diff(solution.q, axis=0)))) / face.dt
        if speed > face.robot.max_joint_speed:
            return Rejection("joint_speed", speed / face.robot.max_joint_speed - 1.0)
        return Solution(plan, solution)

    def simulate(self, solution: Solution, face: Any, capture: Callable[..., None] | None) -> ToolPath:
        """Execute ``solution`` on the ``face``'s simulation core (in the face's ``context``) and return what it
        executed; ``capture(k)`` (where not None) after control step ``k``, or ``capture(k, overlay)`` with what the
        frames draw of the episode so far (:meth:`render_overlay`), and ``capture(-1)`` before the first. Default:
        the core's own record (every sensor at every physics step) along the joint targets with the servos' velocity
        feed-forward; its overlay is the core itself
        (:class:`~rdmp_gym.envs.servo.ServoSimulation`, its record so far)."""
        from ..servo import ServoSimulation
        from ..smoothness import Smoothness

        joints = solution.joints
        scene = face.scene
        plan = face.joint_targets(joints)
        scene.set_arm_state(joints.q[0])
        simulation = ServoSimulation(scene, face.n_steps, face.frame_skip)
        if capture is not None:
            capture(-1)
        simulation.run(plan.q, None if capture is None else lambda k: capture(k, simulation))
        return ToolPath(solution.plan, joints.q, simulation.sensors, simulation.qpos, simulation.qvel, simulation.tip,
                        simulation.steps, simulation.unstable, face.dt, face.frame_skip,
                        face.jerk_ratio(solution.plan.path), float(Smoothness.peak_accel(joints.q, face.dt).max()),
                        face.robot.max_joint_accel)

    def invalid(self, reason: str, severity: float, n_steps: int, context: Any) -> Outcome:
        """The penalty and info of a path refused in ``context`` for ``reason`` with ``severity`` over ``n_steps``
        control steps (default: ``8 + 4 min(severity, 5)``, spread evenly, in the term ``"invalid"``)."""
        cost = np.full(n_steps, (8.0 + 4.0 * min(float(severity), 5.0)) / n_steps)
        return Outcome({"invalid": -float(cost.sum())}, cost, {}, ("invalid",), valid=False, reason=reason)

    def render_overlay(self, renderer: SceneRenderer, context: Any, overlay: Any) -> np.ndarray:
        """The scene's current frame in ``context`` with what the task draws on it: ``overlay``, the task's record of
        the episode so far (what :meth:`simulate` gave ``capture``, the executed episode's :attr:`ToolPath.record`
        afterwards, or what the step twin's book gives; None before the first step). Default: nothing, the scene as
        it is."""
        return renderer.render()

    def step_book(self, face: Any, reward_every: int) -> Any:
        """The task's step interface on the step twin over the episodic ``face``: a
        :class:`~rdmp_gym.envs.step_book.StepBook` of the task's own, or None (the default) for the generic book;
        ``reward_every`` is the twin's reward resolution in control steps, which a book honours or refuses by name."""
        return None


#: IK residuals (position m, angle rad) beyond which a path is unreachable (:meth:`TaskDescription.solve`)
_IK_TOLERANCE = (0.01, 0.1)
