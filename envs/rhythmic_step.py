"""The step twin of every rhythmic task on every robot: one control step per ``step``, on the same simulation core.

``rdmp_gym/{Robot}{Task}Step-v{N}`` (e.g. ``rdmp_gym/ArmarDrumStep-v1``) runs the
episodic face's scene, context, imitation and simulation core (:class:`~rdmp_gym.envs.servo.ServoSimulation`) one
control step at a time. What is the task's own in a step, its step interface, is its book
(:class:`~rdmp_gym.envs.step_book.StepBook`, from
:meth:`TaskDescription.step_book <rdmp_gym.envs.tasks.description.TaskDescription.step_book>`; the generic book
where the task writes none). Per ``step`` (control step ``k``):

1. the action ``a in [-1, 1]^3`` is a coupling term on the DMP, ``c = max_shift * alpha_z * beta_z * a``: the tool's
   target is the book's imitation plan (the episodic action 0) plus the response of the DMP's transformation system
   to the coupling (a critically damped filter, exact for an input held over the control step; a constant ``a``
   moves the path by ``max_shift * a`` metres along the task frame's axes), as the book adjusts it (e.g. kept in
   the robot's reach); ``a_k`` sets the target of step ``k + 1``;
2. the joint targets are the plan's joints plus a damped least-squares correction for the shift at fixed tool
   orientation, with the servos' velocity feed-forward of the plan; the core runs the control step with the task's
   hook, and the book keeps its books of it (e.g. what the tool has done to the task's objects);
3. the reward is the book's: the generic book's is the growth of the episodic reward of the episode so far, judged
   by the task every ``reward_every`` control steps; the last step closes the sum on the episodic reward of the
   executed motion and its info holds the episodic info (``is_success``, ``failure_causes``, ``cost_trace``, the
   task's keys). The episode ends early (``terminated``) where the simulation diverges or the book ends it (e.g. a
   collision that voids the episode).

With ``a = 0`` throughout the twin executes the episodic action 0 exactly (the same joint targets and physics), so
it meets the same success criteria with the same return.

Observation (float32): the book's. The generic book's: ``cos phi, sin phi`` of the imitation's canonical phase, the
task's cue at this step (the drumming task's beat signal), the tool tip in the task frame (m), its velocity (m/s),
and the context; a task's own book observes what its task needs (its
:attr:`~rdmp_gym.envs.step_book.StepBook.observation_space`).
"""

from __future__ import annotations

from typing import Any, ClassVar

import gymnasium as gym
import numpy as np

from rdmp_gym.validation import refuse_settings

from .coupling import axis_shift, coupling_action, coupling_filter, joint_shift, plan_velocity
from .rhythmic_env import RhythmicTaskEnv
from .servo import ServoSimulation
from .step_book import REWARD_EVERY, StepBook

__all__ = ["REFUSED", "RhythmicTaskStepEnv"]

#: settings of the episodic face that no step twin honours, and why (a book refuses more: its ``refused``)
REFUSED = {"record_frames": "the face captures frames in its own rollout, which the twin does not run; record with the "
                            "episodic env's record_episode"}


class RhythmicTaskStepEnv(gym.Env):
    """A rhythmic task one control step at a time; see the module docstring.

    Args:
        max_shift: path shift (m) for a full constant action: one number for all three axes or one per axis.
        reward_every: control steps between the task's judgements of the episode so far (the generic book's reward
            resolution; default 5); a task with its own book may refuse it.
        **kwargs: the episodic face's keywords (:class:`~rdmp_gym.envs.rhythmic_env.RhythmicTaskEnv`: task, robot,
            version, the task's settings); :data:`REFUSED` (``record_frames``) and the book's
            :attr:`~rdmp_gym.envs.step_book.StepBook.refused` are refused by name.
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["rgb_array", "depth_array"], "render_fps": 100}

    def __init__(self, max_shift: float | tuple[float, float, float] = 0.02, reward_every: int | None = None,
                 **kwargs: Any) -> None:
        super().__init__()
        self.max_shift = axis_shift(max_shift)
        if reward_every is not None and (isinstance(reward_every, bool) or not isinstance(reward_every, int)
                                         or reward_every < 1):
            raise ValueError(f"reward_every: expected an integer >= 1, got {reward_every!r}")
        self.episodic = RhythmicTaskEnv(**kwargs)
        face = self.episodic
        every = REWARD_EVERY if reward_every is None else reward_every
        #: the task's step interface (:class:`~rdmp_gym.envs.step_book.StepBook`)
        self.book: StepBook = face.task.step_book(face, every) or StepBook(face, every)
        refuse_settings({**REFUSED, **self.book.refused}, {**kwargs, "reward_every": reward_every}, "the step twin")
        self.render_mode = face.render_mode
        self.metadata = {**self.metadata, "render_fps": max(1, round(face.control_rate))}
        dmp = face.dmp
        self.coupling_scale = self.max_shift * dmp.alpha_z * dmp.alpha_z / 4.0          # alpha_z beta_z
        self._filter = coupling_filter(dmp.canonical.omega * dmp.canonical.tempo, dmp.alpha_z, face.dt)
        self.action_space = gym.spaces.Box(-1.0, 1.0, shape=(3,), dtype=np.float32)
        self.observation_space = self.book.observation_space
        self._simulation: ServoSimulation | None = None

    @property
    def task(self) -> RhythmicTaskEnv:
        """The episodic face (its task's attributes read through it: ``env.unwrapped.task.task_version``)."""
        return self.episodic

    # ------------------------------------------------------------------ gym API
    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        """Draw a context (``options`` as the episodic face's) and put the robot at rest at the imitation's start."""
        super().reset(seed=seed)
        face, book = self.episodic, self.book
        _, info = face.reset(seed=seed, options=options)
        plan, q = book.plan()
        self._plan, self._path = plan, plan.path.copy()
        self._imitation_q, self._q = q, q.copy()
        self._lead = face.scene.servo_lead()
        face.scene.set_arm_state(self._q[0])
        self._simulation = book.start(plan, self._path, self._q)
        self._shift = np.zeros((2, 3))             # (y, z) of the coupling's response, per axis
        self._k, self._done = 0, False
        self._previous = book.position()
        return book.observation(0, self._previous, np.zeros(3)), info

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict]:
        """Advance one control step with the coupling action ``a [3]`` (clipped to [-1, 1]; a wrong shape, NaN or
        infinite values raise ValueError)."""
        if self._simulation is None:
            raise RuntimeError("call reset() before step()")
        if self._done:
            raise RuntimeError("the episode has ended: call reset() before step()")
        a = coupling_action(action)
        face, book, k = self.episodic, self.book, self._k
        count = face.n_steps
        if k + 1 < count:
            self._advance(k + 1, self.coupling_scale * a)
        diverged = self._simulation.step(k, self._q[k] + self._lead * plan_velocity(self._q, k, face.dt))
        book.record(k, diverged)
        self._k = k + 1
        ended = book.ended(k)
        terminated = diverged or ended
        last = terminated or self._k >= count
        reward, info = book.reward(k, last, ended)
        position = book.position()
        observation = book.observation(min(self._k, count - 1), position, (position - self._previous) / face.dt)
        self._previous = position
        self._done = last
        return observation, reward, terminated, last and not terminated, info

    def render(self) -> np.ndarray | None:
        """The current state as the episodic face renders it (with what the book brings up to date for it)."""
        self.book.prepare_render()
        return self.episodic.render()

    def close(self) -> None:
        self.episodic.close()

    # ------------------------------------------------------------------ the plan
    def _advance(self, k: int, coupling: np.ndarray) -> None:
        """Step the coupling's response to control step ``k`` and shift its target (as the book adjusts it) and
        joints by it."""
        transition, gain = self._filter
        self._shift = transition @ self._shift + np.outer(gain, coupling)
        offset = self._shift[0]
        if not np.any(offset):
            return
        target, offset = self.book.target(k, self._plan.path[k], offset)
        self._path[k] = target
        self._q[k] = self._imitation_q[k] + joint_shift(self.episodic.ik.kin, self._imitation_q[k],
                                                          self._plan.rotation @ offset)
