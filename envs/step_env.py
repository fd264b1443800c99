"""``rdmp_gym/ArmarWipeStep-v1``: the wiping task one control step at a time (residual RL on a DMP).

The step-based sibling of the episodic env, as fancy_gym offers one beside each movement-primitive env.
The same scene, context, DMP, controller and reward weights (an :class:`ArmarWipeEnv` inside provides
them); per ``step``:

1. the DMP advances one control step online (``RhythmicDMP.start`` -> :class:`rdmp_gym.DMPStepper`,
   anchored at the dirt patch, started at the sponge start), driven by the **coupling term**
   ``c = max_shift * alpha_z * beta_z * a`` for the action ``a in [-1, 1]^3``: a constant ``a`` moves the
   DMP's equilibrium by ``max_shift * a`` metres, and the second-order system keeps the path smooth;
2. one differential-IK step (warm-started at the last solution) turns the sponge target into joint
   targets; the wrist-force admittance law adapts the pressing depth; MuJoCo runs ``frame_skip`` steps;
3. the reward is the episodic reward split over the steps: ``coverage`` for the cells this step wipes
   first, ``force`` closeness in the periodic phase, and the ``excess_force``, ``contact_loss``,
   ``joint_limit``, ``arm_collision`` penalties, with the episodic env's weights and normalisations, so
   that the return of an episode approximates the episodic reward of the same motion.

Observation (float32): ``cos phi, sin phi, r`` of the canonical system, the sponge position (nominal
table frame, m) and velocity (m/s), the wrist force along the table normal (N / target force), and the
context (``ArmarWipe`` observation). The episode ends (``truncated``) after the episodic env's duration;
a diverged simulation ends it (``terminated``) with the ``unstable`` penalty. ``a = 0`` runs the imitation.
"""

from __future__ import annotations

from typing import Any, ClassVar

import gymnasium as gym
import mujoco
import numpy as np

from rdmp_gym import DMPStepper

from .context import SIZE as CONTEXT_SIZE
from .controller import ForceAdaptation
from .scene import dirt_grid
from .wipe_env import WORKSPACE_HIGH, WORKSPACE_LOW, ArmarWipeEnv
from .wiping import cells_under_sponge

__all__ = ["ArmarWipeStepEnv"]

_MAX_FORCE = 2000.0       # N: a larger wrist force counts as a diverged simulation (as in the episodic env)
_OBS_SIZE = 3 + 3 + 3 + 1 + CONTEXT_SIZE


class ArmarWipeStepEnv(gym.Env):
    """Step-based wiping; see the module docstring.

    Args:
        max_shift: equilibrium shift (m) of the DMP for a full action, per axis.
        ik_iterations: damped-least-squares iterations of the IK per control step (warm-started).
        **kwargs: keywords of :class:`ArmarWipeEnv` (style, demonstration, dmp, n_periods, duration,
            control_rate, target_force, force_band, reward_weights, adaptation, context_ranges, render_mode, ...).
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["human", "rgb_array", "depth_array"], "render_fps": 100}

    def __init__(self, max_shift: float = 0.02, ik_iterations: int = 3, **kwargs: Any) -> None:
        super().__init__()
        if not (np.isfinite(max_shift) and max_shift >= 0.0):
            raise ValueError(f"max_shift: expected a number >= 0 (m), got {max_shift!r}")
        if isinstance(ik_iterations, bool) or int(ik_iterations) != ik_iterations or ik_iterations < 1:
            raise ValueError(f"ik_iterations: expected an integer >= 1, got {ik_iterations!r}")
        self.task = ArmarWipeEnv(**kwargs)
        self.render_mode = self.task.render_mode
        self.metadata = {**self.metadata, "render_fps": max(1, round(self.task.control_rate))}
        self.dmp = self.task.dmp
        self.coupling_scale = float(max_shift) * self.dmp.alpha_z * self.dmp.alpha_z / 4.0
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
        """Draw a context (``options`` as in ``ArmarWipe``), put the robot at rest at the sponge start."""
        super().reset(seed=seed)
        context_obs, info = self.task.reset(seed=seed, options=options)
        task, scene, context = self.task, self.task.scene, self.task.context
        self._context_obs = context_obs
        anchor = np.array([*context.patch_centre, self.dmp.anchor[2]])
        self._stepper = self.dmp.start(task.dt, y0=context.sponge_start, anchor=anchor, start_blend=True)
        start = self.dmp.transients[0]
        self._phase, self._radius = self.dmp.canonical.state(task.times, start.phi0, start.r0)
        origin, rot = scene.table_frame(actual=True)
        cells = dirt_grid(context.patch_centre, context.patch_size, task.cell_size)
        self._cells = np.c_[cells, np.zeros(len(cells))] @ rot.T + origin
        self._table_normal = rot[:, 2]
        self._wiped = np.zeros(len(cells), dtype=bool)
        self._q = scene.arm_qpos()
        self._lead = scene.servo_lead()
        self._adaptation = ForceAdaptation(task.adaptation_settings, task.dt)
        self._bias = float(scene.wrist_force_world() @ scene.nominal_normal)
        self._measured = 0.0
        self._k = 0
        self._previous = context.sponge_start.copy()
        self._n_periodic = max(1, int(np.count_nonzero(task.periodic)))
        return self._observation(context.sponge_start, np.zeros(3)), info

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict]:
        """Advance one control step with the coupling action ``a [3]`` (clipped to [-1, 1])."""
        if self._stepper is None:
            raise RuntimeError("call reset() before step()")
        a = np.asarray(action, dtype=np.float64)
        if a.shape != (3,) or not np.all(np.isfinite(a)):
            raise ValueError(f"action: expected 3 finite values, got shape {a.shape}")
        task, scene = self.task, self.task.scene
        target, _ = self._stepper.step(self.coupling_scale * np.clip(a, -1.0, 1.0))
        target = np.clip(target, WORKSPACE_LOW, WORKSPACE_HIGH)
        q, normal_dq = self._solve(target)
        depth = self._adaptation.update(self._measured, float(target[2]))
        velocity = (q - self._q) / task.dt
        command = np.clip(q + self._lead * velocity - depth * normal_dq, scene.joint_lower, scene.joint_upper)
        self._q = q
        before = scene.data.time
        scene.data.ctrl[scene.actuator_ids] = command
        mujoco.mj_step(scene.model, scene.data, task.frame_skip)
        self._measured = self._bias - float(scene.wrist_force_world() @ scene.nominal_normal)
        unstable = (scene.data.time <= before or not np.isfinite(self._measured)
                    or abs(self._measured) > _MAX_FORCE)
        terms, info = self._reward(unstable)
        self._k += 1
        position = self._sponge_position()
        observation = self._observation(position, (position - self._previous) / task.dt)
        self._previous = position
        truncated = not unstable and self._k >= task.n_steps
        return observation, float(sum(terms.values())), unstable, truncated, info

    def render(self) -> np.ndarray | None:
        """As the episodic env's ``render`` (the current state)."""
        return self.task.render()

    def close(self) -> None:
        self.task.close()

    # ------------------------------------------------------------------ internals
    def _solve(self, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Joint positions [10] and the joint motion per metre along the normal [10] for a sponge target [3]."""
        scene = self.task.scene
        weight = np.clip(1.0 - (target[2] - self.task.adaptation_settings.engage_height) / 0.05, 0.2, 1.0)
        solution = self.task.ik.solve(scene.to_world(target[None], actual=False), scene.nominal_normal,
                                      rot_weight=np.array([weight]), q_init=self._q, stride=1,
                                      coarse_iterations=self.ik_iterations, fine_iterations=0,
                                      min_iterations=self.ik_iterations)
        return solution.q[0], solution.normal_dq[0]

    def _sponge_position(self) -> np.ndarray:
        scene = self.task.scene
        origin, rot = scene.table_frame(actual=False)
        return (scene.data.site_xpos[scene.sponge_site] - origin) @ rot

    def _reward(self, unstable: bool) -> tuple[dict[str, float], dict[str, Any]]:
        """This step's share of the episodic reward terms, and the info dict."""
        task, scene, data = self.task, self.task.scene, self.task.scene.data
        settings, weights = task.reward_settings, task.reward_weights
        rows = data.sensordata[scene.sponge_contact_adr:scene.sponge_contact_adr + 4]
        force = abs(float(rows[1:] @ self._table_normal))
        low, high = task.force_band
        new = 0
        if low <= force <= high:
            pos = data.geom_xpos[scene.sponge_geom][None]
            rot = data.geom_xmat[scene.sponge_geom][None]
            under = cells_under_sponge(self._cells, pos, rot, scene.sponge_half, 0.003)[0] & ~self._wiped
            new = int(under.sum())
            self._wiped |= under
        arm = float(data.sensordata[scene.robot_contact_adr]) - float(rows[0]) > 0.5
        joints = scene.arm_qpos()
        at_limit = bool(np.any((joints < scene.joint_lower + task.limit_margin)
                               | (joints > scene.joint_upper - task.limit_margin)))
        periodic = bool(task.periodic[min(self._k, task.n_steps - 1)])
        count, n_per = task.n_steps, self._n_periodic
        score = np.exp(-0.5 * ((force - settings.target_force) / settings.force_sigma) ** 2)
        excess = min(1.0, max(0.0, force - settings.max_force) / settings.max_force)
        terms = {
            "coverage": weights.coverage * new / max(1, len(self._cells)),
            "force": float(weights.force * score / n_per) if periodic else 0.0,
            "excess_force": -weights.excess_force * excess / count,
            "contact_loss": -weights.contact_loss / n_per if periodic and force < settings.contact_threshold else 0.0,
            "joint_limit": -weights.joint_limit * at_limit / count,
            "arm_collision": -weights.arm_collision * arm / count,
            "unstable": -weights.unstable if unstable else 0.0,
        }
        info = {"reward_terms": terms, "coverage": float(np.mean(self._wiped)) if self._wiped.size else 0.0,
                "contact_force": force, "wrist_force": self._measured, "unstable": unstable}
        return terms, info

    def _observation(self, position: np.ndarray, velocity: np.ndarray) -> np.ndarray:
        k = min(self._k, self.task.n_steps - 1)
        phase, radius = float(self._phase[k]), float(self._radius[k])
        force = self._measured / self.task.reward_settings.target_force
        parts = [np.cos(phase), np.sin(phase), radius, *position, *velocity, force, *self._context_obs]
        return np.clip(np.asarray(parts, dtype=np.float32), self.observation_space.low, self.observation_space.high)
