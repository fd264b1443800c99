"""The wiping task's step interface: :class:`WipeStepBook`, its book on the generic step twin.

``rdmp_gym/ArmarWipeStep-v3`` and ``rdmp_gym/PandaWipeStep-v3`` are the generic step twin
(:class:`~rdmp_gym.envs.rhythmic_step.RhythmicTaskStepEnv` with ``task="wipe"``) with this book
(:meth:`WipingTask.step_book <rdmp_gym.envs.tasks.wiping.task.WipingTask.step_book>`): the twin shifts the episodic
imitation's plan by the coupling's response and steps the simulation core; the book gives it what is the wiping
task's own in a step:

- the plan: the episodic action 0's sponge path and its joint path (the episodic path IK), with the joint motion
  along the control normal that the pressing depth moves;
- the simulation: the core with the wiping hook (:class:`~rdmp_gym.envs.tasks.wiping.simulation.WipeSimulation`:
  admittance law on the pressing depth, servo targets, physics, the record), reading the commanded heights as the
  twin shifts them;
- the shifted sponge target kept in the robot's workspace;
- the dirt worn step by step, and the episode's end (``terminated``) where a robot geom penetrates the robot's body
  or the table beyond the limit;
- the reward: the growth of every episodic reward term of the episode so far at every step (``info["reward_terms"]``);
  the last step closes the sum on the episodic reward of the executed motion (the ``invalid`` reward after a
  penetration), and its info has the episodic statistics, ``is_success``, ``failure_causes`` and the cost traces;
- the observation (float32, 26): ``cos phi, sin phi, r`` of the canonical system, the sponge position (nominal table
  frame, m), its face normal (table frame), its velocity (m/s), the wrist force along the control normal (N / target
  force) and the context (the episodic observation);
- the dirt left drawn on a frame; the settings it cannot honour (:data:`UNSUPPORTED`, and ``reward_every``) are
  refused by name.

With ``a = 0`` throughout, the twin executes the episodic env's action 0 exactly (same joint targets, same physics),
so it meets the same success criteria with the same return. :class:`WipeStepEnv` is a deprecated name of the twin.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np

from ...rhythmic_step import RhythmicTaskStepEnv
from ...servo import ServoSimulation
from ...step_book import StepBook
from ..description import TaskPlan
from .context import SIZE as CONTEXT_SIZE
from .reward import TERMS, Smoothness, invalid_reward, wipe_reward
from .scene import TablePose, WipeParts, control_frame, table_frame
from .simulation import DirtField, WipeSimulation, WipeTrace

__all__ = ["UNSUPPORTED", "WipeStepBook", "WipeStepEnv", "sponge_position"]

_OBS_SIZE = 3 + 3 + 3 + 3 + 1 + CONTEXT_SIZE
#: Settings of the episodic env that the step envs cannot honour (they do not know the path ahead).
UNSUPPORTED = {"cup_clearance": "it pushes a whole planned path away from the cup, and the step twin plans one "
                                "step ahead", "record_frames": "record with the episodic env's record_episode"}


class WipeStepBook(StepBook):
    """The wiping task's step interface; see the module docstring.

    Args:
        face: the episodic face of the wiping task (:class:`~rdmp_gym.envs.rhythmic_env.RhythmicTaskEnv`).
    """

    refused: ClassVar[Mapping[str, str]] = {**UNSUPPORTED,
                                            "reward_every": "the wiping task grows its reward terms at every step"}

    def __init__(self, face: Any) -> None:
        super().__init__(face)
        start = face.dmp.transients[0]
        self._phase, self._radius = face.dmp.canonical.state(face.times, start.phi0, start.r0)
        self._wear: np.ndarray | None = None

    def space(self) -> gym.spaces.Box:
        """The observation's space (float32, 26): the canonical state within 100 (the radius within twice the
        imitation's start if that is more), the sponge's position, face normal and velocity and the wrist force
        within 100, the context ``[13]``."""
        face = self.face
        bound = np.full(_OBS_SIZE, 100.0, dtype=np.float32)
        bound[2] = max(100.0, 2.0 * face.dmp.transients[0].r0)
        bound[-CONTEXT_SIZE:] = np.maximum(np.abs(face.observation_space.low), np.abs(face.observation_space.high))
        return gym.spaces.Box(-bound, bound, dtype=np.float32)

    # ------------------------------------------------------------------ the episode
    def plan(self) -> tuple[TaskPlan, np.ndarray]:
        """The episodic action 0's sponge path ``[T, 3]`` (nominal table frame) in the control frame, and its joint
        path ``[T, n]``."""
        face, task = self.face, self.face.task
        path = task.rollout_path(face.action_to_params(np.zeros(face.action_space.shape)), face.context)
        solution = task.solve_path(path, face.context)
        self._ndq = solution.normal_dq
        origin, rotation = control_frame(task.parts, TablePose.of(face.context))
        normal = rotation[:, 2]
        self._normal = normal / np.linalg.norm(normal)           # as the episodic plan (JointTargetPlan) has it
        return TaskPlan(path, origin, rotation), solution.q

    def start(self, plan: TaskPlan, path: np.ndarray, q: np.ndarray) -> ServoSimulation:
        """The core with the wiping hook, which reads the commanded heights ``path[:, 2]`` as the twin shifts them."""
        face, task = self.face, self.face.task
        scene = face.scene
        context = face.context
        cells = task.dirt_cells(context)
        dirt = DirtField(cells, table_frame(task.parts, TablePose.of(context))[1][:, 2], wear_rate=task.wear_rate,
                         contact_threshold=task.reward_settings.contact_threshold)
        self._simulation = WipeSimulation(scene, task.parts, face.n_steps, task.force_adaptation(), dirt,
                                          face.frame_skip, self._normal, task.simulation_settings, normal_dq=self._ndq,
                                          heights=path[:, 2], cup=context.obstacle)
        core = ServoSimulation(scene, face.n_steps, face.frame_skip, hook=self._simulation)
        self._path, self._q = path, q
        self._context = context.vector().astype(np.float32)
        self._reference = task.imitation_jerk(context)
        self._wear = np.zeros(len(cells))
        self._removed = np.zeros(face.n_steps)
        self._terms = dict.fromkeys(TERMS, 0.0)
        return core

    def target(self, k: int, planned: np.ndarray, offset: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The shifted target kept in the robot's workspace (nominal table frame), and the offset that leaves."""
        low, high = self.face.robot.workspace
        target = np.clip(planned + offset, low, high)
        return target, target - planned

    def record(self, k: int, diverged: bool) -> None:
        """The dirt worn in step ``k`` (the running coverage of the intermediate rewards)."""
        if diverged:
            return
        simulation = self._simulation
        force = abs(float(np.nan_to_num(simulation.contact(k)) @ simulation.dirt.normal))
        box_pos, box_rot = simulation.box_pose(k)
        self._removed[k] = simulation.dirt.add_step(self._wear, force, box_pos, box_rot,
                                                    simulation.box_pose(max(0, k - 1))[0],
                                                    self.face.task.parts.sponge_half)

    def ended(self, k: int) -> bool:
        """A robot geom penetrated the table or the robot's body beyond the limit in step ``k`` or before."""
        simulation, limit = self._simulation, self.face.task.penetration_limit
        return simulation.table_penetration > limit or simulation.self_penetration(k) > limit

    # ------------------------------------------------------------------ reward
    def reward(self, k: int, last: bool, ended: bool) -> tuple[float, dict[str, Any]]:
        """This step's growth of the episodic reward terms (summed), and the info (the episode's at the last step;
        after a penetration, ``ended``, the invalid reward)."""
        face, task = self.face, self.face.task
        traces: dict[str, np.ndarray] = {}
        worn = None if last else (self._removed, 1.0 - np.minimum(self._wear, 1.0))
        trace, smooth = self._simulation.trace(upto=k + 1, wear=worn), self._smoothness(k + 1)
        if ended:
            total, cost = invalid_reward(trace.penetration / 0.05, face.n_steps, task.reward_weights, traces)
        else:
            total, cost = wipe_reward(trace, task.periodic, smooth, task.reward_settings, task.reward_weights, traces)
        terms = {name: total[name] - self._terms[name] for name in TERMS}
        self._terms = total
        info: dict[str, Any] = {"reward_terms": terms, "coverage": trace.coverage, "unstable": trace.unstable,
                                "contact_force": float(trace.contact_force[k]),
                                "wrist_force": self._simulation.measured}
        if last:
            info.update(self._episode_info(trace, smooth, total, cost, traces, ended))
        return float(sum(terms.values())), info

    def _episode_info(self, trace: WipeTrace, smooth: Smoothness, total: dict, cost: np.ndarray, traces: dict,
                      penetrated: bool) -> dict[str, Any]:
        """The episode's statistics, reward terms, cost traces, validity and success."""
        task = self.face.task
        stats = task.statistics(trace, smooth)
        if penetrated:
            task.void_coverage(stats)
        success, causes = task.success(stats, not penetrated, trace.unstable)
        return {**stats, "episode_reward_terms": dict(total), "cost_trace": cost, "cost_terms": traces,
                "valid": not penetrated, "invalid_reason": "penetration" if penetrated else "", "is_success": success,
                "failure_causes": causes}

    def _smoothness(self, steps: int) -> Smoothness:
        """The smoothness of the first ``steps`` steps, padded to the episode (the episodic measure at the end)."""
        task = self.face.task
        if steps == self.face.n_steps:
            return task.smoothness(self._path, self._q, self._reference)
        return task.smoothness(self._path[:steps], self._q[:steps], self._reference).padded(self.face.n_steps)

    # ------------------------------------------------------------------ observation
    def position(self) -> np.ndarray:
        """The sponge's face centre ``[3]`` in the nominal table frame (m)."""
        return sponge_position(self.face.scene.data, self.face.task.parts)

    def observation(self, k: int, position: np.ndarray, velocity: np.ndarray) -> np.ndarray:
        """The observation ``[26]`` at control step ``k`` with the sponge at ``position [3]`` moving at
        ``velocity [3]``."""
        data, parts = self.face.scene.data, self.face.task.parts
        normal = -data.geom_xmat[parts.sponge_geom].reshape(3, 3)[:, 0] @ parts.table_rotation
        force = self._simulation.measured / self.face.task.reward_settings.target_force
        values = [np.cos(self._phase[k]), np.sin(self._phase[k]), self._radius[k], *position, *normal, *velocity,
                  force, *self._context]
        return np.clip(np.asarray(values, dtype=np.float32), self.observation_space.low, self.observation_space.high)

    def prepare_render(self) -> None:
        """The frames draw the dirt left so far (:meth:`dirt_left`)."""
        if self._wear is not None:
            self.face.overlay = self

    def dirt_left(self) -> np.ndarray:
        """Dirt left per cell ``[N]`` in [0, 1], as worn step by step so far."""
        return 1.0 - np.minimum(self._wear, 1.0)


def sponge_position(data: Any, parts: WipeParts) -> np.ndarray:
    """The sponge's face centre ``[3]`` in the nominal table frame (m), in the scene's ``data``."""
    return (data.site_xpos[parts.sponge_site] - parts.table_origin) @ parts.table_rotation


class WipeStepEnv(RhythmicTaskStepEnv):
    """Deprecated name of the wiping task's step twin: the generic step twin with ``task="wipe"``
    (``gym.make("rdmp_gym/ArmarWipeStep-v3")`` or ``RhythmicTaskStepEnv(task="wipe", ...)`` make the same env).

    Args:
        max_shift: path shift (m) for a full constant action: one number for all three axes or one per axis.
        **kwargs: the episodic face's keywords of the wiping task (robot, version, style, n_periods, target_force,
            context_ranges, obstacle, ...); ``cup_clearance``, ``record_frames`` and ``reward_every`` are refused by
            name.
    """

    def __init__(self, max_shift: float | tuple[float, float, float] = 0.02, **kwargs: Any) -> None:
        warnings.warn("WipeStepEnv is deprecated: use gym.make('rdmp_gym/ArmarWipeStep-v3') or "
                      "RhythmicTaskStepEnv(task='wipe', ...), the same env", DeprecationWarning, stacklevel=2)
        super().__init__(max_shift, task="wipe", **kwargs)
