"""The step twin of every rhythmic task on every robot: one control step per ``step``, on the same simulation core.

``rdmp_gym/{Robot}{Task}Step-v{N}`` (e.g. ``rdmp_gym/ArmarDrumStep-v1``) runs the episodic face's scene, context,
imitation plan and simulation core (:class:`~rdmp_gym.envs.servo.ServoSimulation`) one control step at a time:

1. the action ``a in [-1, 1]^3`` is a coupling term on the DMP, ``c = max_shift * alpha_z * beta_z * a``: the tool's
   target is the imitation's plan (the episodic action 0) plus the response of the DMP's transformation system to
   the coupling (a critically damped filter, exact for an input held over the control step; a constant ``a`` moves
   the path by ``max_shift * a`` metres along the task frame's axes); ``a_k`` sets the target of step ``k + 1``;
2. the joint targets are the imitation's planned joints plus a damped least-squares correction for the shift at
   fixed tool orientation, with the servos' velocity feed-forward of the episodic plan;
3. the reward is the growth of the episodic reward of the episode so far, judged by the task every
   ``reward_every`` control steps; the last step closes the sum on the episodic reward of the executed motion and
   its info holds the episodic info (``is_success``, ``failure_causes``, ``cost_trace``, the task's keys).

With ``a = 0`` throughout the twin executes the episodic action 0 exactly (the same joint targets and physics), so
it meets the same success criteria with the same return.

Observation (float32): ``cos phi, sin phi`` of the imitation's canonical phase, the task's cue at this step (the
drumming task's beat signal), the tool tip in the task frame (m), its velocity (m/s), and the context.
"""

from __future__ import annotations

from typing import Any, ClassVar

import gymnasium as gym
import numpy as np

from .coupling import axis_shift, coupling_action, coupling_filter, joint_shift, plan_velocity
from .rhythmic_env import RhythmicTaskEnv
from .servo import ServoSimulation
from .smoothness import Smoothness
from .tasks.description import TaskPlan, ToolPath

__all__ = ["RhythmicTaskStepEnv"]


class RhythmicTaskStepEnv(gym.Env):
    """A rhythmic task one control step at a time; see the module docstring.

    Args:
        max_shift: path shift (m) for a full constant action: one number for all three axes or one per axis.
        reward_every: control steps between the task's judgements of the episode so far (the reward's resolution).
        **kwargs: the episodic face's keywords (:class:`~rdmp_gym.envs.rhythmic_env.RhythmicTaskEnv`: task, robot,
            version, the task's settings).
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["rgb_array"], "render_fps": 100}

    def __init__(self, max_shift: float | tuple[float, float, float] = 0.02, reward_every: int = 5,
                 **kwargs: Any) -> None:
        super().__init__()
        self.max_shift = axis_shift(max_shift)
        if isinstance(reward_every, bool) or not isinstance(reward_every, int) or reward_every < 1:
            raise ValueError(f"reward_every: expected an integer >= 1, got {reward_every!r}")
        self.reward_every = reward_every
        self.episodic = RhythmicTaskEnv(**kwargs)
        self.render_mode = self.episodic.render_mode
        self.metadata = {**self.metadata, "render_fps": max(1, round(self.episodic.control_rate))}
        dmp = self.episodic.dmp
        self.coupling_scale = self.max_shift * dmp.alpha_z * dmp.alpha_z / 4.0          # alpha_z beta_z
        self._filter = coupling_filter(dmp.canonical.omega * dmp.canonical.tempo, dmp.alpha_z, self.episodic.dt)
        self.action_space = gym.spaces.Box(-1.0, 1.0, shape=(3,), dtype=np.float32)
        context = self.episodic.observation_space
        bound = np.full(9 + context.shape[0], 10.0, dtype=np.float32)
        bound[9:] = np.maximum(np.abs(context.low), np.abs(context.high))
        self.observation_space = gym.spaces.Box(-bound, bound, dtype=np.float32)
        self._simulation: ServoSimulation | None = None

    # ------------------------------------------------------------------ gym API
    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        """Draw a context (``options`` as the episodic face's) and put the robot at rest at the imitation's start."""
        super().reset(seed=seed)
        face = self.episodic
        _, info = face.reset(seed=seed, options=options)
        plan = face.imitation_plan
        solution = face.solve_plan(plan, plan.world())
        self._plan, self._path = plan, plan.path.copy()
        self._imitation_q, self._q = solution.q, solution.q.copy()
        self._lead = face.scene.servo_lead()
        face.scene.set_arm_state(self._q[0])
        self._simulation = ServoSimulation(face.scene, face.n_steps, face.frame_skip)
        self._shift = np.zeros((2, 3))
        self._k, self._judged, self._done = 0, 0.0, False
        start = face.dmp.transients[0]
        self._phase = start.phi0 + face.dmp.canonical.omega * face.times
        self._cue = face.task.cue(face.context, face.times)
        self._previous = self._tip()
        return self._observation(self._previous, np.zeros(3)), info

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict]:
        """Advance one control step with the coupling action ``a [3]`` (clipped to [-1, 1]; a wrong shape, NaN or
        infinite values raise ValueError)."""
        if self._simulation is None:
            raise RuntimeError("call reset() before step()")
        if self._done:
            raise RuntimeError("the episode has ended: call reset() before step()")
        a = coupling_action(action)
        face, k = self.episodic, self._k
        count = face.n_steps
        if k + 1 < count:
            self._advance(k + 1, self.coupling_scale * a)
        diverged = self._simulation.step(k, self._q[k] + self._lead * plan_velocity(self._q, k, face.dt))
        self._k = k + 1
        last = diverged or self._k >= count
        reward, info = self._reward(last)
        tip = self._tip()
        observation = self._observation(tip, (tip - self._previous) / face.dt)
        self._previous = tip
        self._done = last
        return observation, reward, diverged, last and not diverged, info

    def render(self) -> np.ndarray | None:
        """The current state as the episodic face renders it."""
        return self.episodic.render()

    def close(self) -> None:
        self.episodic.close()

    # ------------------------------------------------------------------ the plan
    def _advance(self, k: int, coupling: np.ndarray) -> None:
        """Step the coupling's response to control step ``k`` and shift its target and joints by it."""
        transition, gain = self._filter
        self._shift = transition @ self._shift + np.outer(gain, coupling)
        offset = self._shift[0]
        if not np.any(offset):
            return
        self._path[k] = self._plan.path[k] + offset
        self._q[k] = self._imitation_q[k] + joint_shift(self.episodic.ik.kin, self._imitation_q[k],
                                                          self._plan.rotation @ offset)

    # ------------------------------------------------------------------ reward
    def _reward(self, last: bool) -> tuple[float, dict[str, Any]]:
        """The growth of the episodic reward so far (judged every ``reward_every`` steps and at the last), and the
        info (the episode's at the last step)."""
        steps = self._k
        if not last and steps % self.reward_every:
            return 0.0, {}
        face, simulation = self.episodic, self._simulation
        executed = simulation.steps if last else steps
        plan = TaskPlan(self._path, self._plan.origin, self._plan.rotation, self._plan.extras)
        record = ToolPath(plan, self._q, simulation.sensors, simulation.qpos, simulation.qvel, simulation.tip,
                          executed, simulation.unstable, face.dt, face.frame_skip, face.jerk_ratio(self._path),
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
    def _tip(self) -> np.ndarray:
        """The tool tip ``[3]`` in the task frame (m)."""
        scene = self.episodic.scene
        return (scene.data.site_xpos[scene.tip_site] - self._plan.origin) @ self._plan.rotation

    def _observation(self, tip: np.ndarray, velocity: np.ndarray) -> np.ndarray:
        k = min(self._k, self.episodic.n_steps - 1)
        parts = [np.cos(self._phase[k]), np.sin(self._phase[k]), self._cue[k], *tip, *velocity,
                 *self.episodic.context.vector()]
        return np.clip(np.asarray(parts, dtype=np.float32), self.observation_space.low, self.observation_space.high)
