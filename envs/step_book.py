"""A task's step interface: :class:`StepBook`, what the step twin asks of a task one control step at a time.

The step twin (:class:`~rdmp_gym.envs.rhythmic_step.RhythmicTaskStepEnv`) owns what every task's step interface
shares: the gym API, the coupling action's filter, the shifted path and joints, the servo targets with their velocity
feed-forward and the core's control step. A task's book owns the rest, episode by episode:

- the imitation **plan** the twin shifts (:meth:`StepBook.plan`: the task plan and its joint path);
- the **simulation** on the core, with the task's hook (:meth:`StepBook.start`);
- the **shifted target** of a control step (:meth:`StepBook.target`, e.g. kept in the robot's reach);
- the per-step **bookkeeping** after the core's step (:meth:`StepBook.record`) and an **early end**
  (:meth:`StepBook.ended`: ``terminated``);
- the step's **reward and info** (:meth:`StepBook.reward`; at the last step the episode's info);
- the **observation** and its space (:attr:`StepBook.observation_space`, :meth:`StepBook.position`,
  :meth:`StepBook.observation`), what a frame needs (:meth:`StepBook.prepare_render`) and the settings the twin
  refuses by name (:attr:`StepBook.refused`).

:class:`StepBook` itself is the generic book, the twin's way for a task that writes none
(:meth:`TaskDescription.step_book <rdmp_gym.envs.tasks.description.TaskDescription.step_book>` returns None): the
face's imitation plan, the core's own record, the target as shifted, no end but a diverged simulation, the growth of
the task's episodic reward judged every ``reward_every`` control steps, and the tool tip observed.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, ClassVar

import gymnasium as gym
import numpy as np

from .servo import ServoSimulation
from .smoothness import Smoothness
from .tasks.description import TaskPlan, ToolPath

if TYPE_CHECKING:
    from .rhythmic_env import RhythmicTaskEnv

__all__ = ["REWARD_EVERY", "StepBook"]

#: control steps between the generic book's judgements of the episode so far, unless the twin is given its own
REWARD_EVERY = 5


class StepBook:
    """The generic step interface of a task; see the module docstring. A task's own book subclasses it.

    Args:
        face: the episodic face the twin runs on (reset by the twin before :meth:`plan`).
        reward_every: control steps between the task's judgements of the episode so far (the reward's resolution).
    """

    #: settings of the twin and the face that the twin refuses for this task: name -> why (a value other than None or
    #: False is refused)
    refused: ClassVar[Mapping[str, str]] = {}

    def __init__(self, face: RhythmicTaskEnv, reward_every: int = REWARD_EVERY) -> None:
        self.face = face
        self.reward_every = reward_every
        #: the observation's space (:meth:`space`)
        self.observation_space = self.space()

    def space(self) -> gym.spaces.Box:
        """The observation's space (float32): ``cos phi, sin phi`` of the imitation's canonical phase, the task's cue,
        the tool tip ``[3]`` (task frame, m), its velocity ``[3]`` (m/s), within 10, and the context ``[C]``."""
        context = self.face.observation_space
        bound = np.full(9 + context.shape[0], 10.0, dtype=np.float32)
        bound[9:] = np.maximum(np.abs(context.low), np.abs(context.high))
        return gym.spaces.Box(-bound, bound, dtype=np.float32)

    # ------------------------------------------------------------------ the episode
    def plan(self) -> tuple[TaskPlan, np.ndarray]:
        """The imitation's plan in this episode's context and its joint path ``[T, n]`` (the face's inverse
        kinematics)."""
        face = self.face
        plan = face.imitation_plan
        return plan, face.solve_plan(plan, plan.world()).q

    def start(self, plan: TaskPlan, path: np.ndarray, q: np.ndarray) -> ServoSimulation:
        """The episode's simulation core, the robot at rest at ``q[0]``; ``path [T, 3]`` and ``q [T, n]`` are the
        shifted plan, which the twin writes one control step ahead of the core."""
        face = self.face
        self._plan, self._path, self._q = plan, path, q
        self._simulation = ServoSimulation(face.scene, face.n_steps, face.frame_skip)
        self._judged = 0.0
        start = face.dmp.transients[0]
        self._phase = start.phi0 + face.dmp.canonical.omega * face.times
        self._cue = face.task.cue(face.context, face.times)
        return self._simulation

    def target(self, k: int, planned: np.ndarray, offset: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The tool's target ``[3]`` at control step ``k``: the planned point ``planned [3]`` shifted by the coupling's
        ``offset [3]`` (task frame, m), and the offset the joints follow."""
        return planned + offset, offset

    def record(self, k: int, diverged: bool) -> None:
        """The task's bookkeeping after the core ran control step ``k`` (the generic book: the core's record)."""

    def ended(self, k: int) -> bool:
        """Whether the task ends the episode after control step ``k`` (``terminated``; the generic book: never, only a
        diverged simulation ends it early)."""
        return False

    # ------------------------------------------------------------------ reward
    def reward(self, k: int, last: bool, ended: bool) -> tuple[float, dict[str, Any]]:
        """The reward of control step ``k`` and its info (the episode's at the ``last`` step; ``ended``: the task
        ended the episode): the growth of the episodic reward so far, judged every ``reward_every`` steps and at the
        last."""
        steps = k + 1
        if not last and steps % self.reward_every:
            return 0.0, {}
        face, simulation = self.face, self._simulation
        plan = TaskPlan(self._path, self._plan.origin, self._plan.rotation, self._plan.extras)
        record = ToolPath(plan, self._q, simulation.sensors, simulation.qpos, simulation.qvel, simulation.tip, steps,
                          simulation.unstable, face.dt, face.frame_skip, face.jerk_ratio(self._path),
                          float(Smoothness.peak_accel(self._q, face.dt).max()), face.robot.max_joint_accel)
        outcome = face.task.evaluate(record, face.context, face.scene.sensor)
        judged = -float(np.sum(outcome.cost_trace)) if last else -float(np.sum(outcome.cost_trace[:steps]))
        reward, self._judged = judged - self._judged, judged
        if not last:
            return reward, {}
        causes = ("unstable",) if simulation.unstable else outcome.causes
        return reward, {**outcome.info, "reward_terms": outcome.terms, "cost_trace": outcome.cost_trace,
                        "valid": True, "invalid_reason": "", "unstable": simulation.unstable,
                        "is_success": not causes, "failure_causes": causes, "episode_reward": judged}

    # ------------------------------------------------------------------ observation
    def position(self) -> np.ndarray:
        """The tool tip ``[3]`` in the task frame (m)."""
        scene = self.face.scene
        return (scene.data.site_xpos[scene.tip_site] - self._plan.origin) @ self._plan.rotation

    def observation(self, k: int, position: np.ndarray, velocity: np.ndarray) -> np.ndarray:
        """The observation at control step ``k`` with the tool at ``position [3]`` moving at ``velocity [3]`` (the
        twin's finite difference of :meth:`position`)."""
        parts = [np.cos(self._phase[k]), np.sin(self._phase[k]), self._cue[k], *position, *velocity,
                 *self.face.context.vector()]
        return np.clip(np.asarray(parts, dtype=np.float32), self.observation_space.low, self.observation_space.high)

    def prepare_render(self) -> None:
        """Bring up to date what the face draws before it renders a frame (the generic book: nothing)."""
