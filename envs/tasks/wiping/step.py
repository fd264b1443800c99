"""``rdmp_gym/ArmarWipeStep-v3`` and ``rdmp_gym/PandaWipeStep-v3``: the wiping task one control step at a time.

The step twin of the episodic env (as fancy_gym offers one beside each movement-primitive env) runs the same
simulation core (:class:`~rdmp_gym.envs.servo.ServoSimulation` with the wiping task's hook
:class:`~rdmp_gym.envs.tasks.wiping.simulation.WipeSimulation`: admittance law, servo targets, physics, wear,
bookkeeping) on the same task description, scene, context, DMP and plan. Per ``step`` (control step ``k``):

1. the action ``a in [-1, 1]^3`` is a coupling term ``c = max_shift * alpha_z * beta_z * a`` on the DMP: the path
   is the episodic imitation's path (action 0 of the episodic env) plus the response of the DMP's
   transformation system to the coupling (a second-order, critically damped filter, exact for an input held over
   the control step): a constant ``a`` moves the path by ``max_shift * a`` metres, smoothly. ``a_k`` sets the
   sponge target of step ``k + 1``;
2. the joint path is the imitation's planned joint path (the episodic path IK) plus a damped least-squares
   correction for the coupling's shift at fixed sponge orientation; the servo targets add the episodic plan's
   velocity feed-forward (``np.gradient`` of the joint path, which needs the next step's joints: hence 1.);
3. the simulation core runs the control step; the reward is the growth of the episodic reward of the episode so
   far (its dirt worn step by step), and the last step's reward closes the sum on the episodic reward of the
   executed motion, every term as the episodic env computes it.

With ``a = 0`` throughout, the twin executes the episodic env's action 0 exactly (same joint targets, same
physics), so it meets the same success criteria with the same return. An episode ends early (``terminated``)
when the simulation diverges or a robot geom penetrates the robot's body or the table beyond the limit; the last
step's info has the episodic statistics, ``is_success``, ``failure_causes`` and the cost traces.

Observation (float32, 26): ``cos phi, sin phi, r`` of the canonical system, the sponge position (nominal table
frame, m), its face normal (table frame), its velocity (m/s), the wrist force along the control normal (N / target
force) and the context (the episodic observation).

This twin is the wiping task's own, not the generic step twin
(:class:`~rdmp_gym.envs.rhythmic_step.RhythmicTaskStepEnv`): its observation, its reward terms grown at every step,
its target kept in the workspace and its end on a penetration are the task's published step interface, which the
generic twin (the tool tip, a reward judged every few steps) does not have; it runs on the generic episodic face
(``self.task``, a :class:`~rdmp_gym.envs.rhythmic_env.RhythmicTaskEnv` of the wiping task).
"""

from __future__ import annotations

from typing import Any, ClassVar

import gymnasium as gym
import numpy as np

from ...coupling import axis_shift, coupling_action, coupling_filter, joint_shift, plan_velocity
from ...servo import ServoSimulation
from .context import SIZE as CONTEXT_SIZE
from .env import ArmarWipeEnv, outcome
from .reward import TERMS, Smoothness, invalid_reward, wipe_reward
from .scene import WipeScene
from .simulation import DirtField, WipeSimulation, WipeTrace

__all__ = ["UNSUPPORTED", "WipeStepEnv", "sponge_position"]

_OBS_SIZE = 3 + 3 + 3 + 3 + 1 + CONTEXT_SIZE
#: Settings of the episodic env that the step twin cannot honour (it does not know the path ahead).
UNSUPPORTED = {"cup_clearance": "it pushes a whole planned path away from the cup, and the step twin plans one "
                                "step ahead", "record_frames": "record with the episodic env's record_episode"}



class WipeStepEnv(gym.Env):
    """Step-based wiping on the simulation core; see the module docstring.

    Args:
        max_shift: path shift (m) for a full constant action: one number for all three axes or one per axis.
        **kwargs: the episodic env's keywords (:class:`~rdmp_gym.envs.tasks.wiping.env.ArmarWipeEnv`: robot, version,
            style, n_periods, target_force, context_ranges, obstacle, ...); ``cup_clearance`` and
            ``record_frames`` are refused by name.
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["rgb_array", "depth_array"], "render_fps": 100}

    def __init__(self, max_shift: float | tuple[float, float, float] = 0.02, **kwargs: Any) -> None:
        super().__init__()
        for key, why in UNSUPPORTED.items():
            if kwargs.get(key) not in (None, False):
                raise ValueError(f"{key}: the step twin cannot honour it ({why})")
        self.max_shift = axis_shift(max_shift)
        self.task = ArmarWipeEnv(**kwargs)
        self.render_mode = self.task.render_mode
        self.metadata = {**self.metadata, "render_fps": max(1, round(self.task.control_rate))}
        dmp = self.task.dmp
        self.coupling_scale = self.max_shift * dmp.alpha_z * dmp.alpha_z / 4.0          # alpha_z beta_z
        self._filter = coupling_filter(dmp.canonical.omega * dmp.canonical.tempo, dmp.alpha_z, self.task.dt)
        self.action_space = gym.spaces.Box(-1.0, 1.0, shape=(3,), dtype=np.float32)
        bound = np.full(_OBS_SIZE, 100.0, dtype=np.float32)
        bound[2] = max(100.0, 2.0 * dmp.transients[0].r0)
        bound[-CONTEXT_SIZE:] = np.maximum(np.abs(self.task.observation_space.low),
                                           np.abs(self.task.observation_space.high))
        self.observation_space = gym.spaces.Box(-bound, bound, dtype=np.float32)
        self._simulation: WipeSimulation | None = None

    # ------------------------------------------------------------------ gym API
    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        """Draw a context (``options`` as the episodic env's) and put the robot at rest at the sponge start."""
        super().reset(seed=seed)
        task = self.task
        self._context_obs, info = task.reset(seed=seed, options=options)
        self._plan_imitation()
        scene = task.scene
        scene.set_arm_state(self._q[0])
        dirt = DirtField(task.dirt_cells, scene.table_frame(actual=True)[1][:, 2], wear_rate=task.wear_rate,
                         contact_threshold=task.reward_settings.contact_threshold)
        self._adaptation = task.force_adaptation()
        self._simulation = WipeSimulation(scene, task.n_steps, self._adaptation, dirt, task.frame_skip,
                                          self._normal, task.simulation_settings, normal_dq=self._ndq,
                                          heights=self._path[:, 2])
        self._core = ServoSimulation(scene, task.n_steps, task.frame_skip, hook=self._simulation)
        self._wear = np.zeros(len(task.dirt_cells))
        self._removed = np.zeros(task.n_steps)
        self._shift = np.zeros((2, 3))             # (y, z) of the coupling's response, per axis
        self._k = 0
        self._terms = dict.fromkeys(TERMS, 0.0)
        self._done = False
        position = sponge_position(self.task.scene)
        self._previous = position
        return self._observation(position, np.zeros(3)), info

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict]:
        """Advance one control step with the coupling action ``a [3]`` (clipped to [-1, 1]; a wrong shape, NaN or
        infinite values raise ValueError)."""
        if self._simulation is None:
            raise RuntimeError("call reset() before step()")
        if self._done:
            raise RuntimeError("the episode has ended: call reset() before step()")
        a = coupling_action(action)
        task, k, count = self.task, self._k, self.task.n_steps
        if k + 1 < count:
            self._advance(k + 1, self.coupling_scale * a)
        row = self._q[k] + self._lead * plan_velocity(self._q, k, self.task.dt)
        diverged = self._core.step(k, row)
        self._wear_step(k, diverged)
        self._k = k + 1
        penetrated = self._simulation.table_penetration > task.penetration_limit or self._self_penetration(k)
        last = diverged or penetrated or self._k >= count
        terms, info = self._reward(k, last, penetrated)
        position = sponge_position(self.task.scene)
        observation = self._observation(position, (position - self._previous) / task.dt)
        self._previous = position
        terminated = diverged or penetrated
        truncated = not terminated and self._k >= count
        self._done = terminated or truncated
        return observation, float(sum(terms.values())), terminated, truncated, info

    def render(self) -> np.ndarray | None:
        """The current state as the episodic env renders it (with the dirt left so far)."""
        if self._simulation is not None:
            self.task.dirt_left = 1.0 - np.minimum(self._wear, 1.0)
        return self.task.render()

    def close(self) -> None:
        self.task.close()

    # ------------------------------------------------------------------ the plan
    def _plan_imitation(self) -> None:
        """The episodic action 0's path and joint path, which the coupling's response shifts step by step."""
        task = self.task
        theta = task.action_to_params(np.zeros(task.action_space.shape))
        self._path = task.rollout_path(theta)
        solution = task.solve_path(self._path)
        self._imitation_q = solution.q
        self._q, self._ndq = solution.q.copy(), solution.normal_dq
        self._rotation = task.scene.control_frame()[1]
        normal = self._rotation[:, 2]
        self._normal = normal / np.linalg.norm(normal)           # as the episodic plan (JointTargetPlan) has it
        self._lead = task.scene.servo_lead()
        dmp, start = task.dmp, task.dmp.transients[0]
        self._phase, self._radius = dmp.canonical.state(task.times, start.phi0, start.r0)

    def _advance(self, k: int, coupling: np.ndarray) -> None:
        """Step the coupling's response to control step ``k`` and shift its target and joints by it."""
        transition, gain = self._filter
        self._shift = transition @ self._shift + np.outer(gain, coupling)
        offset = self._shift[0]
        if not np.any(offset):
            return
        low, high = self.task.robot.workspace
        target = np.clip(self._path[k] + offset, low, high)
        offset = target - self._path[k]
        self._path[k] = target
        self._q[k] = self._imitation_q[k] + joint_shift(self.task.ik.kin, self._imitation_q[k], self._rotation @ offset)


    # ------------------------------------------------------------------ bookkeeping
    def _wear_step(self, k: int, diverged: bool) -> None:
        """The dirt worn in step ``k`` (the running coverage of the intermediate rewards)."""
        if diverged:
            return
        simulation = self._simulation
        force = abs(float(np.nan_to_num(simulation.contact(k)) @ simulation.dirt.normal))
        box_pos, box_rot = simulation.box_pose(k)
        self._removed[k] = simulation.dirt.add_step(self._wear, force, box_pos, box_rot,
                                                    simulation.box_pose(max(0, k - 1))[0],
                                                    self.task.scene.sponge_half)

    def _self_penetration(self, k: int) -> bool:
        return self._simulation.self_penetration(k) > self.task.penetration_limit

    def _reward(self, k: int, last: bool, penetrated: bool) -> tuple[dict[str, float], dict[str, Any]]:
        """This step's growth of the episodic reward terms, and the info dict (the episode's at the last step)."""
        task = self.task
        traces: dict[str, np.ndarray] = {}
        worn = None if last else (self._removed, 1.0 - np.minimum(self._wear, 1.0))
        trace, smooth = self._simulation.trace(upto=k + 1, wear=worn), self._smoothness(k + 1)
        if penetrated:
            total, cost = invalid_reward(trace.penetration / 0.05, task.n_steps, task.reward_weights, traces)
        else:
            total, cost = wipe_reward(trace, task.periodic, smooth, task.reward_settings, task.reward_weights, traces)
        terms = {name: total[name] - self._terms[name] for name in TERMS}
        self._terms = total
        info: dict[str, Any] = {"reward_terms": terms, "coverage": trace.coverage, "unstable": trace.unstable,
                                "contact_force": float(trace.contact_force[k]),
                                "wrist_force": self._simulation.measured}
        if last:
            info.update(self._episode_info(trace, smooth, total, cost, traces, penetrated))
        return terms, info

    def _episode_info(self, trace: WipeTrace, smooth: Smoothness, total: dict, cost: np.ndarray, traces: dict,
                      penetrated: bool) -> dict[str, Any]:
        task = self.task
        stats = task.statistics(trace, smooth)
        if penetrated and task.task_version.void_coverage:
            stats["simulated_coverage"], stats["coverage"] = stats["coverage"], 0.0
        success, causes = outcome(stats, not penetrated, trace.unstable, task.success_joint_accel,
                                  task.task_version.max_jerk_ratio)
        return {**stats, "episode_reward_terms": dict(total), "cost_trace": cost, "cost_terms": traces,
                "valid": not penetrated, "invalid_reason": "penetration" if penetrated else "", "is_success": success,
                "failure_causes": causes}

    def _smoothness(self, steps: int) -> Smoothness:
        """The smoothness of the first ``steps`` steps, padded to the episode (the episodic measure at the end)."""
        task = self.task
        if steps == task.n_steps:
            return task.smoothness(self._path, self._q)
        return task.smoothness(self._path[:steps], self._q[:steps]).padded(task.n_steps)

    # ------------------------------------------------------------------ observation
    def _observation(self, position: np.ndarray, velocity: np.ndarray) -> np.ndarray:
        task, scene = self.task, self.task.scene
        k = min(self._k, task.n_steps - 1)
        face = -scene.data.geom_xmat[scene.sponge_geom].reshape(3, 3)[:, 0] @ scene.table_frame(actual=False)[1]
        force = self._simulation.measured / task.reward_settings.target_force
        parts = [np.cos(self._phase[k]), np.sin(self._phase[k]), self._radius[k], *position, *face, *velocity, force,
                 *self._context_obs]
        return np.clip(np.asarray(parts, dtype=np.float32), self.observation_space.low, self.observation_space.high)


def sponge_position(scene: WipeScene) -> np.ndarray:
    """The sponge's face centre ``[3]`` in the nominal table frame (m)."""
    origin, rot = scene.table_frame(actual=False)
    return (scene.data.site_xpos[scene.sponge_site] - origin) @ rot
