"""``rdmp_gym/ArmarWipeStep-v1``: the wiping task one control step at a time (residual RL on a DMP).

The step-based sibling of ``ArmarWipe-v1``, as fancy_gym offers one beside each movement-primitive env:
the same scene (tilted table, Preston dirt, the cup), context, DMP, controller and reward terms; the
generic episodic face of the wiping task inside (:class:`ArmarWipeEnv`) provides them. It keeps its own class
(not the generic step twin with the wiping task's step book, which shifts a planned path) because its DMP runs online
and its inverse kinematics solves one target per step, the published v1/v2 step interface. Per ``step`` (control
step ``k``):

1. the DMP runs online (``RhythmicDMP.start(start_blend=True)`` -> :class:`rdmp_gym.DMPStepper`, anchored at
   the dirt patch, started at the sponge start), driven by the **coupling term**
   ``c = max_shift * alpha_z * beta_z * a`` for the action ``a in [-1, 1]^3``: a constant ``a`` moves the
   DMP's equilibrium by ``max_shift * a`` metres and the second-order system keeps the path smooth. The
   sponge target of step ``k`` is the DMP's ``y_k``; ``a_k`` sets ``y_{k+1}``;
2. differential IK in the v1 control frame (nominal table origin, actual tilt) turns the
   targets into joint targets, with the episodic plan's velocity feed-forward (central difference, using
   the solution for ``y_{k+1}``) and the wrist-force admittance law on the pressing depth; MuJoCo runs
   ``frame_skip`` steps on the simulation core (:class:`~rdmp_gym.envs.servo.ServoSimulation`, with this env as
   its hook: one physics step at a time for 0.2 s after the first contact, to catch the impact);
3. the measurements of the step are appended to a :class:`WipeTrace` of the episode so far, and the
   reward is the growth of the episodic reward: ``r_k = R(trace_0..k) - R(trace_0..k-1)`` with
   ``R = sum(wipe_reward(...))``, the v1 reward function itself. The return of an episode is therefore
   exactly the episodic reward of the motion that was executed (every term: coverage by Preston wear,
   force, excess force, contact loss, impact, smoothness against the imitation, joint acceleration,
   arm and self-collision, the cup, joint limits, unstable). ``info["reward_terms"]`` splits ``r_k``.

Where the episodic env rejects a whole path before simulating it (workspace, IK, joint speed), a step
env cannot: the bounded action keeps the path within ``max_shift`` of the imitation's equilibrium and the
target is clipped to the workspace. A penetration of the robot's body or the table beyond the episodic
limit ends the episode (``terminated``) with the episodic ``invalid`` reward as its return; a diverged
simulation ends it with the ``unstable`` charge. The last step's info has the episodic statistics,
``is_success`` (same thresholds), ``failure_causes`` and the cost traces (``cost_trace``, ``cost_terms``).

Observation (float32, 26): ``cos phi, sin phi, r`` of the canonical system, the sponge position (nominal
table frame, m), its face normal (table frame), its velocity (m/s), the wrist force along the control
normal (N / target force) and the context (``ArmarWipe-v1``'s 13-d observation, with the cup).
``a = 0`` runs the imitation.
"""

from __future__ import annotations

from typing import Any, ClassVar

import gymnasium as gym
import numpy as np

from rdmp_gym import DMPStepper
from rdmp_gym.validation import refuse_settings

from ....controller import ForceAdaptation
from ....coupling import axis_shift, coupling_action, plan_velocity
from ....servo import ServoSimulation
from ..context import SIZE as CONTEXT_SIZE
from ..env import ArmarWipeEnv
from ..reward import TERMS, Smoothness, invalid_reward, wipe_reward
from ..scene import TablePose, control_frame, table_frame, to_world, wrist_force_world
from ..simulation import IMPACT_WINDOW, DirtField, WipeTrace, arm_table_penetration
from ..step import UNSUPPORTED, sponge_position

__all__ = ["REFUSED", "ArmarWipeStepEnv"]


#: Settings of the episodic env that this step env cannot honour, and why: the step twin's, and the learned depth
#: profile (this env runs its own control loop with the plain admittance law).
REFUSED = {**UNSUPPORTED, "force_learning": "it learns the pressing depth over the periods of a planned episode; this "
                                            "step env runs the plain admittance law (use the v3 step twin)"}
_MAX_FORCE = 2000.0       # N: a larger wrist or contact force is a diverged simulation (as in simulate_wipe)
_OBS_SIZE = 3 + 3 + 3 + 3 + 1 + CONTEXT_SIZE


class ArmarWipeStepEnv(gym.Env):
    """Step-based wiping; see the module docstring.

    Args:
        max_shift: equilibrium shift (m) of the DMP for a full action: one number for all three axes or one per
            axis (``ArmarWipeStep-v2``: 6 cm along the table, 2 cm in height, so that the policy can carry the
            pattern across a large patch: the step-based form of the episodic env's sweep).
        ik_iterations: damped-least-squares iterations of the IK per control step, a fixed count from the IK's
            posture (as the episodic path IK solves its knots; a warm start drifts in the null space, and
            stopping at a tolerance after a varying count makes the joint targets jump between steps).
        **kwargs: keywords of :class:`ArmarWipeEnv` (version 1, the default, or 2; style, demonstration, dmp,
            n_periods, duration, control_rate, target_force, force_band, reward_weights, adaptation, context_ranges,
            obstacle, render_mode, ...);
            ``cup_clearance``, ``record_frames`` and ``force_learning`` are refused by name (:data:`REFUSED`).
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["human", "rgb_array", "depth_array"], "render_fps": 100}

    def __init__(self, max_shift: float | tuple[float, float, float] = 0.02, ik_iterations: int = 30,
                 **kwargs: Any) -> None:
        super().__init__()
        refuse_settings(REFUSED, kwargs, "the v1/v2 step env")
        kwargs.setdefault("version", 1)
        if kwargs["version"] not in (1, 2):
            raise ValueError(f"version: this step env runs the versions 1 and 2, got {kwargs['version']!r}; "
                             f"version 3's step twin is rdmp_gym/ArmarWipeStep-v3")
        shift = axis_shift(max_shift)
        if isinstance(ik_iterations, bool) or not isinstance(ik_iterations, (int, np.integer)) or ik_iterations < 1:
            raise ValueError(f"ik_iterations: expected an integer >= 1, got {ik_iterations!r}")
        self.task = ArmarWipeEnv(**kwargs)
        #: the wiping task's description (the face's)
        self.wiping = self.task.task
        self.render_mode = self.task.render_mode
        self.metadata = {**self.metadata, "render_fps": max(1, round(self.task.control_rate))}
        self.dmp = self.task.dmp
        #: ``[3]`` equilibrium shift (m) per axis at a full action
        self.max_shift = shift
        self.coupling_scale = self.max_shift * self.dmp.alpha_z * self.dmp.alpha_z / 4.0   # alpha_z beta_z
        self.ik_iterations = int(ik_iterations)
        self.action_space = gym.spaces.Box(-1.0, 1.0, shape=(3,), dtype=np.float32)
        bound = np.full(_OBS_SIZE, 100.0, dtype=np.float32)
        bound[2] = max(100.0, 2.0 * self.dmp.transients[0].r0)
        bound[-CONTEXT_SIZE:] = np.maximum(np.abs(self.task.observation_space.low),
                                           np.abs(self.task.observation_space.high))
        self.observation_space = gym.spaces.Box(-bound, bound, dtype=np.float32)
        self._stepper: DMPStepper | None = None

    # ------------------------------------------------------------------ gym API
    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        """Draw a context (``options`` as in ``ArmarWipe-v1``) and put the robot at rest at the sponge start."""
        super().reset(seed=seed)
        context_obs, info = self.task.reset(seed=seed, options=options)
        task, scene, context = self.task, self.task.scene, self.task.context
        assert context is not None
        count = task.n_steps
        self._context_obs = context_obs
        anchor = np.array([*context.patch_centre, self.dmp.anchor[2]])
        self._stepper = self.dmp.start(task.dt, y0=context.sponge_start, anchor=anchor, start_blend=True)
        start = self.dmp.transients[0]
        self._phase, self._radius = self.dmp.canonical.state(task.times, start.phi0, start.r0)
        self._parts, self._pose, self._cup = self.wiping.parts, TablePose.of(context), context.obstacle
        self._normal = control_frame(self._parts, self._pose)[1][:, 2]
        self._table_normal = table_frame(self._parts, self._pose)[1][:, 2]
        cells = self.wiping.dirt_cells(context)
        self._dirt = DirtField(cells, self._table_normal, wear_rate=self.wiping.wear_rate,
                               contact_threshold=self.wiping.reward_settings.contact_threshold)
        self._wear = np.zeros(len(cells))
        self._reference = self.wiping.imitation_jerk(context)
        task.overlay = self
        # the episode so far: commanded path and joints, and the per-step records of a WipeTrace
        self._path = np.zeros((count, 3))
        self._q = np.zeros((count, scene.qpos_adr.size))
        self._ndq = np.zeros((count, scene.qpos_adr.size))
        self._path[0] = self._clip(context.sponge_start)
        self._ik_start = task.ik.posture
        self._q[0], self._ndq[0] = self._solve(self._path[0], self._ik_start)
        scene.set_arm_state(self._q[0])
        self._rec = {name: np.zeros(count) for name in ("contact_force", "wrist_force", "depth", "removed", "peak",
                                                       "obstacle_shift")}
        for name in ("arm_contact", "self_contact", "obstacle_contact", "at_limit"):
            self._rec[name] = np.zeros(count, dtype=bool)
        self._box_pos = np.zeros((count, 3))
        self._sponge_pos = np.zeros((count, 3))
        self._penetration, self._first_contact = 0.0, -1
        self._fine_window = max(1, round(IMPACT_WINDOW / task.dt))
        cup = self._parts.obstacle_qpos
        self._obstacle_start = scene.data.qpos[cup:cup + 3].copy()
        self._adaptation = ForceAdaptation(self.wiping.adaptation_settings, task.dt)
        self._bias = float(wrist_force_world(scene.data, self._parts) @ self._normal)
        self._lead = scene.servo_lead()
        self._measured = 0.0
        self._depth, self._top, self._before = 0.0, 0.0, 0.0
        self._core = ServoSimulation(scene, count, task.frame_skip, hook=self)
        self._k = 0
        self._terms = dict.fromkeys(TERMS, 0.0)
        self._done = False
        position = sponge_position(self.task.scene.data, self._parts)
        self._previous = position
        return self._observation(position, np.zeros(3)), info

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict]:
        """Advance one control step with the coupling action ``a [3]`` (clipped to [-1, 1]; a wrong shape, NaN
        or infinite values raise ValueError)."""
        if self._stepper is None:
            raise RuntimeError("call reset() before step()")
        if self._done:
            raise RuntimeError("the episode has ended: call reset() before step()")
        a = coupling_action(action)
        task, k = self.task, self._k
        count = task.n_steps
        if k + 1 < count:                                  # the action sets the next target y_{k+1}
            target, _ = self._stepper.step(self.coupling_scale * a)
            self._path[k + 1] = self._clip(target)
            self._q[k + 1], self._ndq[k + 1] = self._solve(self._path[k + 1], self._ik_start)
        q = self._q
        velocity = plan_velocity(q, k, task.dt)             # np.gradient of the episodic JointTargetPlan
        unstable = self._core.step(k, q[k] + self._lead * velocity)
        self._k = k + 1
        penetrated = self._penetration > self.wiping.penetration_limit
        terms, info = self._reward(k, unstable, penetrated)
        position = sponge_position(self.task.scene.data, self._parts)
        observation = self._observation(position, (position - self._previous) / task.dt)
        self._previous = position
        terminated = unstable or penetrated
        truncated = not terminated and self._k >= count
        self._done = terminated or truncated
        return observation, float(sum(terms.values())), terminated, truncated, info

    def render(self) -> np.ndarray | None:
        """As the episodic env's ``render`` (the current state, with the dirt left so far)."""
        return self.task.render()

    def dirt_left(self) -> np.ndarray:
        """Dirt left per cell ``[N]`` in [0, 1] so far (what the frames draw)."""
        return 1.0 - np.minimum(self._wear, 1.0)

    def close(self) -> None:
        self.task.close()

    # ------------------------------------------------------------------ internals
    def _clip(self, target: np.ndarray) -> np.ndarray:
        return np.clip(target, *self.task.robot.workspace)

    def _solve(self, target: np.ndarray, q_init: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Joint positions [10] and joint motion per metre along the normal [10] for a sponge target [3]
        (nominal table frame), as the episodic env's IK (control frame, orientation weight) from ``q_init``."""
        weight = np.clip(1.0 - (target[2] - self.wiping.adaptation_settings.engage_height) / 0.05, 0.2, 1.0)
        solution = self.task.ik.solve(to_world(self._parts, self._pose, target[None]), self._normal,
                                      rot_weight=np.array([weight]), q_init=q_init, stride=1,
                                      coarse_iterations=self.ik_iterations, fine_iterations=1,
                                      min_iterations=self.ik_iterations)
        return solution.q[0], solution.normal_dq[0]

    # ------------------------------------------------------------------ its hook on the simulation core
    def command(self, k: int, target: np.ndarray) -> None:
        """The servo targets of control step ``k``: ``target`` (the joints and their feed-forward) less the pressing
        depth of the admittance law along the normal."""
        scene = self.task.scene
        self._before = scene.data.time
        depth = self._adaptation.update(self._measured, float(self._path[k, 2]))
        scene.data.ctrl[scene.actuator_ids] = target - depth * self._ndq[k]
        self._depth = depth

    def substeps(self, k: int) -> bool:
        """One physics step at a time within the impact window after the first contact."""
        if self._first_contact >= 0 and k < self._first_contact + self._fine_window:
            self._top = 0.0
            return True
        return False

    def substep(self, k: int, i: int) -> None:
        """The peak sponge-table force of the step so far."""
        a = self._parts.sponge_contact_adr
        self._top = max(self._top, abs(float(self.task.scene.data.sensordata[a + 1:a + 4] @ self._table_normal)))

    def finish(self, k: int) -> bool:
        """Record control step ``k`` after its physics (as ``simulate_wipe``); True if it diverged."""
        scene, parts = self.task.scene, self._parts
        d, rec = scene.data, self._rec
        a = parts.sponge_contact_adr
        before, depth = self._before, self._depth
        if self._first_contact >= 0 and k < self._first_contact + self._fine_window:
            rec["peak"][k] = self._top
        sensors = d.sensordata
        if self._first_contact < 0 and sensors[a] > 0:
            self._first_contact = k
        ft_rot = d.site_xmat[parts.ft_site].reshape(3, 3)
        self._measured = self._bias - float(self._normal @ (ft_rot @ sensors[parts.force_adr]))
        force = abs(float(np.nan_to_num(sensors[a + 1:a + 4]) @ self._table_normal))
        rec["contact_force"][k] = force
        rec["wrist_force"][k] = self._measured
        rec["depth"][k] = depth
        rec["arm_contact"][k] = sensors[parts.robot_contact_adr] - sensors[a] > 0.5
        for adr in parts.self_contact_adr:
            if sensors[adr] > 0:
                rec["self_contact"][k] = True
                self._penetration = max(self._penetration, -float(sensors[adr + 1]))
        if rec["arm_contact"][k]:
            self._penetration = max(self._penetration, arm_table_penetration(d, parts))
        rec["obstacle_contact"][k] = sensors[parts.obstacle_contact_adr] > 0
        if self._cup:
            shift = d.qpos[parts.obstacle_qpos:parts.obstacle_qpos + 3] - self._obstacle_start
            rec["obstacle_shift"][k] = float(np.linalg.norm(shift))
        joints = d.qpos[scene.qpos_adr]
        rec["at_limit"][k] = bool(np.any((joints < scene.joint_lower + self.wiping.limit_margin)
                                         | (joints > scene.joint_upper - self.wiping.limit_margin)))
        self._sponge_pos[k] = d.site_xpos[parts.sponge_site]
        box_pos, box_rot = d.geom_xpos[parts.sponge_geom].copy(), d.geom_xmat[parts.sponge_geom].copy()
        self._box_pos[k] = box_pos
        unstable = (d.time <= before or self._measured != self._measured or abs(self._measured) > _MAX_FORCE
                    or force > _MAX_FORCE)
        if not unstable:                                   # Preston wear of this step (DirtField, as the episode)
            rec["removed"][k] = self._dirt.add_step(self._wear, force, box_pos, box_rot,
                                                    self._box_pos[max(0, k - 1)], parts.sponge_half)
        else:
            rec["contact_force"][k] = 0.0 if not np.isfinite(force) else min(force, _MAX_FORCE)
        return bool(unstable)

    def _trace(self, steps: int, unstable: bool) -> tuple[WipeTrace, Smoothness]:
        """The episode so far as the episodic env's trace and smoothness (the first ``steps`` control steps)."""
        rec, task = self._rec, self.task
        impact_step, impact_force = -1, 0.0
        if self._first_contact >= 0:
            peak = np.maximum(rec["peak"], rec["contact_force"])
            window = slice(self._first_contact, min(steps, self._first_contact + self._fine_window))
            impact_step = self._first_contact + int(np.argmax(peak[window]))
            impact_force = float(peak[impact_step])
        trace = WipeTrace(rec["contact_force"], rec["wrist_force"], rec["depth"], rec["removed"],
                          1.0 - np.minimum(self._wear, 1.0), rec["arm_contact"], rec["self_contact"],
                          rec["obstacle_contact"], rec["obstacle_shift"], rec["at_limit"], self._sponge_pos,
                          self._penetration, impact_force, impact_step, None, steps, unstable)
        smooth = self.wiping.smoothness(self._path[:steps], self._q[:steps], self._reference)
        return trace, smooth.padded(task.n_steps)

    def _reward(self, k: int, unstable: bool, penetrated: bool) -> tuple[dict[str, float], dict[str, Any]]:
        """This step's growth of the episodic reward terms, and the info dict."""
        task = self.task
        traces: dict[str, np.ndarray] = {}
        trace, smooth = self._trace(k + 1, unstable)
        last = unstable or penetrated or k + 1 >= task.n_steps
        if penetrated:
            total, cost = invalid_reward(self._penetration / 0.05, task.n_steps, self.wiping.reward_weights, traces)
        else:
            wiping = self.wiping
            total, cost = wipe_reward(trace, wiping.periodic, smooth, wiping.reward_settings, wiping.reward_weights,
                                      traces)
        terms = {name: total[name] - self._terms[name] for name in TERMS}
        self._terms = total
        contact = self._rec["contact_force"][k]
        info: dict[str, Any] = {"reward_terms": terms, "coverage": trace.coverage, "contact_force": float(contact),
                                "wrist_force": self._measured, "unstable": unstable}
        if last:
            stats = self.wiping.statistics(trace, smooth)
            valid = not penetrated
            success, causes = self.wiping.success(stats, valid, unstable)
            info.update(stats)
            info.update({"episode_reward_terms": dict(total), "cost_trace": cost, "cost_terms": traces, "valid": valid,
                         "invalid_reason": "penetration" if penetrated else "", "unstable": unstable,
                         "is_success": success, "failure_causes": causes})
        return terms, info

    def _observation(self, position: np.ndarray, velocity: np.ndarray) -> np.ndarray:
        data, parts = self.task.scene.data, self._parts
        k = min(self._k, self.task.n_steps - 1)
        phase, radius = float(self._phase[k]), float(self._radius[k])
        face = -data.geom_xmat[parts.sponge_geom].reshape(3, 3)[:, 0] @ parts.table_rotation
        force = self._measured / self.wiping.reward_settings.target_force
        parts = [np.cos(phase), np.sin(phase), radius, *position, *face, *velocity, force, *self._context_obs]
        return np.clip(np.asarray(parts, dtype=np.float32), self.observation_space.low, self.observation_space.high)
