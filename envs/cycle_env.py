"""The cycle-level face of every rhythmic task: one ``step`` is one cycle of the DMP, chosen from what is observed.

``rdmp_gym/{Robot}{Task}Cycle-v{N}`` (e.g. ``rdmp_gym/ArmarWipeCycle-v3``) runs the episodic face's task
(:class:`~rdmp_gym.envs.rhythmic_env.RhythmicTaskEnv`) on the same simulation core, cycle by cycle:

- **the cycles** start at the movement's start and then at every crossing of the DMP's canonical phase through its
  initial value after the transient (:func:`rdmp_gym.dmp.cycles.cycle_starts`; the task may declare its own,
  :meth:`~rdmp_gym.envs.tasks.description.TaskDescription.cycle_starts`);
- **the observation** at a cycle's start: the context, what the task reports of the episode there
  (:meth:`~rdmp_gym.envs.tasks.description.TaskDescription.cycle_state`: by default where the tool is and how far
  it is from its path; the wiping task adds the dirt left) and the cycle's place in the episode (its start over
  the duration);
- **the action** of cycle ``k`` has the episodic face's layout: the parameters ``theta_k = theta_imitation + scale a_k``
  and the task's own values, which take over from the movement so far at the cycle's start within half a period
  (:func:`rdmp_gym.dmp.cycles.blend_from`): the path is unchanged before the start, C3 across the hand-over, and
  the new parameters' own path after it (a task whose plan has a state of its own, the drumming task's rhythm
  follower, resumes it from the cycle's start: :meth:`~rdmp_gym.envs.tasks.description.TaskDescription.resume_plan`).
  The first step's action starts the episode as the episodic face's would;
  an action equal to the previous cycle's changes nothing, so the zero action in every cycle is the episodic
  face's action 0, bit for bit. A change the task refuses (its parameter check, reach, joint speed) is not applied:
  ``info["refused"]`` names the reason and the cycle goes on with the previous parameters;
- **the reward** is the episode's, given at its last step (the task judges the whole executed episode); the last
  step's ``info`` is the episodic face's, with the cycles' starts (``"cycle_starts"``, s) and the refused changes.

The simulation of an episode runs in a worker thread that waits at each cycle's start for the next action, so a
cycle's change costs one plan and one inverse kinematics of the path, not a new simulation.
"""

from __future__ import annotations

import queue
import threading
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np

from rdmp_gym.dmp.cycles import DEFAULT_HANDOVER, blend_from

from .contract import TaskContract
from .rhythmic_env import RhythmicTaskEnv
from .tasks.description import Rejection, TaskPlan

__all__ = ["RhythmicCycleEnv"]


class _Abort(Exception):
    """Raised in the worker to end an episode that is left (reset or close before its end)."""


class RhythmicCycleEnv(gym.Env):
    """One cycle per ``step`` of a rhythmic task on a robot; see the module docstring.

    Args:
        handover: the hand-over window of a cycle's change, in periods (default a half).
        **face: the episodic face's keywords (``task``, ``robot``, ``version``, ``render_mode``, the task's
            settings; see :class:`~rdmp_gym.envs.rhythmic_env.RhythmicTaskEnv`).
    """

    metadata: ClassVar[dict[str, Any]] = RhythmicTaskEnv.metadata

    def __init__(self, handover: float = DEFAULT_HANDOVER, **face: Any):
        super().__init__()
        if not (np.isfinite(handover) and 0 < handover <= 1):
            raise ValueError(f"handover: expected a number in (0, 1] (periods), got {handover!r}")
        self.face = RhythmicTaskEnv(**face)
        self.task = self.face.task
        self.render_mode = self.face.render_mode
        self.handover = float(handover) * self.face.dmp.period
        self.action_space = self.face.action_space
        #: cycle start times ``[K]`` (s) and the control step each starts at ``[K]``
        self.starts = np.asarray(self.task.cycle_starts(self.face), dtype=np.float64)
        self.start_steps = np.searchsorted(self.face.times - self.face.times[0], self.starts, side="right")
        self.start_steps[0] = 0
        context_low, context_high = self.task.context_bounds()
        state_low, state_high = self.task.cycle_state_bounds()
        low = np.r_[context_low, state_low, 0.0].astype(np.float32)
        high = np.r_[context_high, state_high, 1.0].astype(np.float32)
        self.observation_space = gym.spaces.Box(low, high, dtype=np.float32)
        self._cycle = 0
        self._actions: list[np.ndarray] = []
        self._refused: list[tuple[int, str]] = []
        #: the plan the running episode last took over (None: the episode's first, the solution's)
        self._plan: TaskPlan | None = None
        self._worker: threading.Thread | None = None
        self._to_main: queue.Queue = queue.Queue(maxsize=1)
        self._to_worker: queue.Queue = queue.Queue(maxsize=1)
        self._state = np.zeros(len(state_low))

    @property
    def n_cycles(self) -> int:
        """Cycles (steps) of an episode."""
        return len(self.starts)

    @property
    def executed_actions(self) -> list[np.ndarray]:
        """The actions of the episode's cycles so far as they run (a refused change gives the previous cycle's),
        copies."""
        return [action.copy() for action in self._actions]

    def task_contract(self) -> TaskContract:
        """The episodic face's contract (:meth:`RhythmicTaskEnv.task_contract`): the last step's info holds its
        metrics."""
        return self.face.task_contract()

    # ------------------------------------------------------------------ gym API
    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        """Leave any running episode, draw a context as the episodic face does and observe the first cycle's
        start (the robot at rest)."""
        super().reset(seed=seed)
        self._abort()
        _, info = self.face.reset(seed=seed, options=options)
        self._cycle, self._actions, self._refused, self._plan = 0, [], [], None
        self._state = np.clip(self.task.cycle_state(self.face, None, None), *self.task.cycle_state_bounds())
        return self._observation(), info

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict]:
        """Run the cycle with the parameters of ``action [n]`` (clipped to [-1, 1]) up to the next cycle's start, or
        to the episode's end (``terminated=True``, the episode's reward and info)."""
        if self.face.context is None:
            raise RuntimeError("call reset() before step()")
        if self._cycle >= self.n_cycles:
            raise RuntimeError("the episode has ended: call reset()")
        action = self.face._check_action(action)
        if self._cycle == 0:
            self._start(action)
        else:
            self._change(action)
            self._to_worker.put("go")
        self._actions.append(action)
        kind, payload = self._to_main.get()
        self._cycle += 1
        if kind == "error":
            self._worker = None
            raise payload
        if kind == "done":
            self._worker = None
            self._cycle = self.n_cycles
            reward, info = payload
            info.update({"cycle_starts": self.starts.copy(), "cycles_run": len(self._actions),
                         "refused": list(self._refused)})
            return self._observation(), reward, True, False, info
        self._state = np.clip(self.task.cycle_state(self.face, payload[0], payload[1]),
                              *self.task.cycle_state_bounds())
        return self._observation(), 0.0, False, False, {"cycle": self._cycle, "refused": list(self._refused)}

    def render(self) -> np.ndarray | None:
        """The episodic face's :meth:`~RhythmicTaskEnv.render` of the current state."""
        return self.face.render()

    def close(self) -> None:
        """Leave any running episode and close the episodic face."""
        self._abort()
        self.face.close()

    # ------------------------------------------------------------------ the episode's worker
    def _start(self, action: np.ndarray) -> None:
        """Start the episode's simulation with the first cycle's parameters in a worker thread."""
        theta, extras = self.face._split(action)
        self.face.control_listener = self._listen
        self._worker = threading.Thread(target=self._run, args=(theta, extras), daemon=True)
        self._worker.start()

    def _run(self, theta: np.ndarray, extras: np.ndarray) -> None:
        try:
            self._to_main.put(("done", self.face._evaluate(theta, extras)))
        except _Abort:
            pass
        except BaseException as error:        # handed to the caller of step()
            self._to_main.put(("error", error))

    def _listen(self, k: int, overlay: Any) -> None:
        """After control step ``k`` (in the worker): at the next cycle's start, report and wait for its action."""
        following = self._cycle + 1
        if following < self.n_cycles and k + 1 == self.start_steps[following]:
            self._to_main.put(("cycle", (k + 1, overlay)))
            if self._to_worker.get() == "abort":
                raise _Abort

    def _abort(self) -> None:
        """End a running episode's worker (it unwinds at its next cycle start)."""
        worker, self._worker = self._worker, None
        if worker is not None and worker.is_alive():
            self._to_worker.put("abort")
            worker.join()
        self.face.control_listener = None
        self._drain()

    def _drain(self) -> None:
        for channel in (self._to_main, self._to_worker):
            while not channel.empty():
                channel.get_nowait()

    # ------------------------------------------------------------------ a cycle's change
    def _change(self, action: np.ndarray) -> None:
        """Hand the running episode over to the parameters of ``action`` from this cycle's start on (in place,
        while the worker waits), or note why the task refuses them."""
        if np.array_equal(action, self._actions[-1]):
            return
        face, cycle = self.face, self._cycle
        theta, extras = face._split(action)
        rejection = self.task.check_params(theta)
        if rejection is None:
            step = int(self.start_steps[cycle])
            new = face.resume_plan(theta, extras, self._plan or face.solution.plan, step)
            rejection = self._handover(new, self.starts[cycle], step)
            if rejection is None:
                self._plan = new
        if rejection is not None:
            self._refused.append((cycle, rejection.reason))
            action[:] = self._actions[-1]          # the cycle goes on with the previous parameters

    def _handover(self, new: TaskPlan, start: float, step: int) -> Rejection | None:
        """Blend the running solution into ``new``'s from ``start`` (s; control step ``step`` is the first that
        changes); the task's refusal of the blended path where it refuses it."""
        face, live = self.face, self.face.solution
        elapsed = face.times - face.times[0]
        path = blend_from(live.plan.path, new.path, elapsed, start, self.handover)
        solution = self.task.solve(TaskPlan(path, live.plan.origin, live.plan.rotation, live.plan.extras), face)
        if isinstance(solution, Rejection):
            return solution
        path = blend_from(live.plan.path, solution.plan.path, elapsed, start, self.handover)
        q = blend_from(live.joints.q, solution.joints.q, elapsed, start, self.handover)
        normal_dq = blend_from(live.joints.normal_dq, solution.joints.normal_dq, elapsed, start, self.handover)
        live.plan.path[step:] = path[step:]
        face.live_targets.follow(step, q, normal_dq)
        return None

    def _observation(self) -> np.ndarray:
        start = self.starts[min(self._cycle, self.n_cycles - 1)]
        progress = start / (self.face.n_steps * self.face.dt)
        return np.r_[self.face.context.vector(), self._state, progress].astype(np.float32)
