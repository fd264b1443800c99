"""What an env knows of a task: one :class:`TaskDescription` per task, as a robot is one description.

A task description holds everything task-specific, so that one episodic face
(:class:`~rdmp_gym.envs.rhythmic_env.RhythmicTaskEnv`) and one step twin
(:class:`~rdmp_gym.envs.rhythmic_step.RhythmicTaskStepEnv`) serve every robot x task on one simulation core
(:class:`~rdmp_gym.envs.servo.ServoSimulation`):

- the **objects** it adds to the room (:meth:`compose`: its tool on the robot's mount, its objects, its sensors);
- the **context** (:meth:`context_bounds`, :meth:`sample_context`, :meth:`place`): what ``reset`` draws, checks and
  observes, and how the objects move for it;
- the **imitation** (:meth:`imitation`): the DMP fitted to the task's demonstration, and the **action layout**
  (:attr:`groups`, :attr:`scales`, :attr:`extras`: DMP parameter groups and the task's own action dimensions);
- the **plan** (:meth:`plan`): the tool path of parameters in a context (the DMP rolled out as the task runs it);
- the **bookkeeping, reward and success** (:meth:`evaluate`): from the simulation's record, the reward terms, the
  per-control-step cost trace, the info keys, ``is_success`` and the failure causes;
- the **learner defaults** (:attr:`learner_defaults`): settings a learner may read from the task, by agent name.

Adding a task is one folder with its description and one line in :data:`rdmp_gym.envs.tasks.TASKS` (or a call of
:func:`rdmp_gym.envs.tasks.register_task` from user code).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

if TYPE_CHECKING:          # the registry imports this module without MuJoCo (string entry points)
    import mujoco

    from rdmp_gym import RhythmicDMP

    from ..robots import RobotDescription

__all__ = ["Outcome", "TaskDescription", "TaskPlan", "ToolPath"]


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
    """

    terms: dict[str, float]
    cost_trace: np.ndarray
    info: dict[str, Any]
    causes: tuple[str, ...]


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
    #: episode length (s) and control rate (Hz)
    duration: float = 8.0
    control_rate: float = 100.0
    #: settings a learner may read from the task: ``{agent: {option: value}}``
    learner_defaults: Mapping[str, Mapping[str, Any]] = {}
    #: the envs that run the task where they are its own, not the rhythmic face (None: the rhythmic face)
    own_faces: ClassVar[str | None] = None

    @classmethod
    def defaults_for(cls, version: int) -> Mapping[str, Mapping[str, Any]]:
        """The learner defaults of the task's ``version`` (default: :attr:`learner_defaults` for every version)."""
        return cls.learner_defaults

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

    @abstractmethod
    def evaluate(self, path: ToolPath, context: Any, sensor: Mapping[str, slice]) -> Outcome:
        """The reward terms, cost trace, info and failure causes of an executed episode; ``sensor`` maps the
        scene's sensor names to their columns of ``path.sensors``."""

    def cue(self, context: Any, times: np.ndarray) -> np.ndarray:
        """What the task signals to the robot at the control times ``times [T]`` (a step-based policy observes it;
        default: nothing, zeros)."""
        return np.zeros(len(times))

    def workspace(self, robot: RobotDescription) -> tuple[np.ndarray, np.ndarray]:
        """The box ``(low [3], high [3])`` of the table frame the tool tip may be commanded in."""
        return robot.workspace
