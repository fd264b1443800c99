"""The wiping task on the simulation core: contact forces, dirt wear, collisions, the obstacle.

:class:`WipeSimulation` is the wiping task's hook on the core (:class:`~rdmp_gym.envs.servo.ServoSimulation`,
``frame_skip`` physics steps per control step); :func:`simulate_wipe` runs a whole episode with it. Per control
step the hook does only what must happen online: the wrist-force adaptation of the pressing depth on the servo
targets, and a copy of the per-step measurements; for 0.2 s after the first sponge contact the core steps the
physics one step at a time for it, to catch the touchdown's peak force (the impact). Everything else is evaluated
afterwards, vectorised over the episode:

- the sponge–table normal force is the net force of MuJoCo's sponge–table contacts (the model's
  ``sponge_table`` contact sensor, i.e. ``mj_contactForce`` summed over exactly those contacts in C),
  projected on the actual table normal; :func:`contact_summary` recomputes it from ``data.contact``;
- dirt wears by a Preston-type law (:class:`DirtField`): at a control step with sponge–table force F,
  every dirt cell under the sponge face loses ``wear_rate * p * s`` of its (unit) dirt, where
  ``p = F / face area`` is the contact pressure and ``s`` the distance the face slid over the table
  since the previous step. Standing still (``s = 0``) or hovering (``F = 0``) removes nothing; the
  coverage is the fraction of the dirt removed;
- an arm collision is a contact of a robot geom other than the sponge with the table; a self-collision
  a contact of the moving arm with a link of the robot's own body (sensors ``arm_<link>``,
  :mod:`rdmp_gym.envs.tasks.wiping.arena`); for both the deepest penetration is recorded;
- the obstacle: whether the arm touches it (sensor ``arm_obstacle``) and how far it has moved.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

from ...controller import ForceAdaptation, JointTargetPlan
from ...servo import ServoSimulation
from .scene import WipeParts, wrist_force_world

__all__ = ["IMPACT_WINDOW", "DirtField", "SimulationSettings", "WipeSimulation", "WipeTrace", "arm_table_penetration",
           "cells_under_sponge", "contact_summary", "simulate_wipe"]

#: Time after the first sponge contact (s) in which the peak normal force is the impact.
IMPACT_WINDOW = 0.2
#: Sponge poses per matrix product in :func:`cells_under_sponge`.
_POSES_PER_PRODUCT = 64


@dataclass(frozen=True)
class DirtField:
    """Dirt cells on the actual table and their wear law.

    Attributes:
        world: cell centres on the table surface in the world frame, [N, 3].
        normal: the actual table normal in the world frame, [3].
        wear_rate: Preston coefficient (1 / (Pa m)): dirt removed per cell per pascal of contact pressure
            per metre slid (a cell holds 1 unit of dirt).
        contact_threshold: a sponge–table force below this (N) wears nothing.
        depth_tolerance: a cell counts as under the sponge only if the sponge face is within this
            distance (m) of it along the face normal (a tilted sponge touches with one edge only).
    """

    world: np.ndarray
    normal: np.ndarray
    wear_rate: float = 2.0e-3
    contact_threshold: float = 1.0
    depth_tolerance: float = 0.003

    def wear(self, force: np.ndarray, slide: np.ndarray, box_pos: np.ndarray, box_rot: np.ndarray,
             half: np.ndarray) -> np.ndarray:
        """Cumulative wear ``[K, N]`` after each of ``K`` control steps (dirt left = ``max(0, 1 - wear)``).

        Args:
            force: sponge–table normal force per step, [K] (N).
            slide: distance the sponge face slid along the table in each step, [K] (m).
            box_pos, box_rot: sponge box pose per step, [K, 3] and [K, 9].
            half: sponge box half sizes [3] (the face is the -x side, area ``4 half[1] half[2]``).
        """
        rows, cumulative = self.wear_steps(force, slide, box_pos, box_rot, half)
        return _carry_forward(rows, cumulative, len(force))

    def add_step(self, wear: np.ndarray, force: float, box_pos: np.ndarray, box_rot: np.ndarray,
                 previous_pos: np.ndarray, half: np.ndarray) -> float:
        """Add one control step's wear to the cumulative ``wear [N]`` (in place) and return the fraction of all
        the dirt it removed; the sponge box moved from ``previous_pos [3]`` to ``box_pos [3]`` (orientation
        ``box_rot [9]``) pressing with normal force ``force`` (N). For loops that run one step at a time."""
        step = box_pos - previous_pos
        slide = float(np.linalg.norm(step - (step @ self.normal) * self.normal))
        done = np.minimum(wear, 1.0).sum()
        wear += self.wear(np.array([force]), np.array([slide]), box_pos[None], box_rot[None], half)[0]
        return (np.minimum(wear, 1.0).sum() - done) / max(1, wear.size)

    def wear_steps(self, force: np.ndarray, slide: np.ndarray, box_pos: np.ndarray, box_rot: np.ndarray,
                   half: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The steps ``[R]`` that remove dirt and the cumulative wear ``[R, N]`` after each of them (between
        them it does not change); :meth:`wear` row for row, without the ``[K, N]`` array."""
        pressure = np.where(force >= self.contact_threshold, force, 0.0) / (4.0 * half[1] * half[2])
        dose = self.wear_rate * pressure * slide                      # [K]: dirt removed under the face
        rows = np.flatnonzero(dose > 0)
        wear = np.empty((rows.size, len(self.world)))
        chunk = max(1, 200_000 // max(1, len(self.world)))
        for start in range(0, rows.size, chunk):
            part = rows[start:start + chunk]
            under = cells_under_sponge(self.world, box_pos[part], box_rot[part], half, self.depth_tolerance)
            wear[start:start + part.size] = under * dose[part, None]
        return rows, np.cumsum(wear, axis=0)


def _carry_forward(rows: np.ndarray, values: np.ndarray, count: int) -> np.ndarray:
    """``[count, ...]``: ``values[j]`` from step ``rows[j]`` until the next row, zeros before ``rows[0]``."""
    full = np.zeros((count, *values.shape[1:]))
    latest = np.searchsorted(rows, np.arange(count), side="right") - 1       # the last row at or before each step
    full[latest >= 0] = values[latest[latest >= 0]]
    return full


@dataclass(frozen=True)
class SimulationSettings:
    """What the simulation core records and how it judges a step.

    Attributes:
        limit_margin: distance to a joint limit (rad) counted as "at the limit".
        max_force: any wrist or contact force above this (N) counts as a diverged simulation.
        fine_force: also record the sponge–table force at every physics step (``trace.fine_force``).
        cup_from_touch: measure the cup's displacement from where it stood just before the robot first touched
            it (zero before): a cup that settles untouched has not moved (else from where it was placed).
    """

    limit_margin: float = 0.02
    max_force: float = 2000.0
    fine_force: bool = False
    cup_from_touch: bool = False


@dataclass
class WipeTrace:
    """Per-control-step record of a simulated wipe (``T`` control steps, ``N`` dirt cells).

    Attributes:
        contact_force: normal force of the sponge–table contacts, [T] (N).
        wrist_force: bias-corrected wrist force along the control normal, + = pressing, [T] (N).
        depth: commanded pressing depth (preload + adapted offset), [T] (m).
        removed: fraction of all the dirt removed in each step, [T] (sums to the coverage).
        dirt: dirt left per cell at the end, [N] in [0, 1].
        arm_contact: a robot geom other than the sponge touches the table, [T].
        self_contact: the moving arm touches a link of the robot's own body, [T].
        obstacle_contact: the moving arm touches the obstacle, [T].
        obstacle_shift: distance of the obstacle's centre from where it stood, [T] (m; 0 without one).
        at_limit: a controlled joint is within the margin of a limit, [T].
        sponge_pos: sponge face centre (on the hand), [T, 3] (world).
        penetration: deepest penetration of a robot geom into the robot's body or (other than the
            sponge) into the table, over the episode (m, >= 0).
        impact_force: peak sponge–table force within :data:`IMPACT_WINDOW` of the first contact (N).
        impact_step: the control step of that peak (-1 without contact).
        fine_force: sponge–table force at every physics step, [T * frame_skip] (only when asked for).
        steps: number of valid control steps (``T`` unless unstable).
        unstable: the simulation diverged (NaN, MuJoCo's reset on bad accelerations, or a force above
            the limit) at step ``steps - 1``; later entries are zero.
    """

    contact_force: np.ndarray
    wrist_force: np.ndarray
    depth: np.ndarray
    removed: np.ndarray
    dirt: np.ndarray
    arm_contact: np.ndarray
    self_contact: np.ndarray
    obstacle_contact: np.ndarray
    obstacle_shift: np.ndarray
    at_limit: np.ndarray
    sponge_pos: np.ndarray
    penetration: float
    impact_force: float
    impact_step: int
    fine_force: np.ndarray | None
    steps: int
    unstable: bool

    @property
    def coverage(self) -> float:
        """Fraction of the dirt removed."""
        return float(1.0 - self.dirt.mean()) if self.dirt.size else 0.0


def cells_under_sponge(cells: np.ndarray, pos: np.ndarray, rot: np.ndarray, half: np.ndarray,
                       tolerance: float) -> np.ndarray:
    """Which cells lie under the sponge's face, for K sponge poses: bool ``[K, N]``.

    Args:
        cells: cell centres, world frame, [N, 3].
        pos: sponge box centres, [K, 3]; rot: sponge box orientations (row-major 3x3), [K, 9].
        half: the sponge box half sizes [3]; the face is the box side at -x.
        tolerance: how far (m) beyond the face plane a cell may lie and still count.
    """
    count = len(pos)
    rot = rot.reshape(count, 3, 3)
    # local[n, k, :] = R_k^T (c_n - p_k), as row vectors: c_n R_k - p_k R_k. The cell terms of 64 poses are
    # one [N, 3] x [3, 192] product (the same sums as 64 products [N, 3] x [3, 3]; small enough that BLAS
    # stays on one thread)
    columns = rot.transpose(1, 0, 2).reshape(3, 3 * count)
    cell_terms = np.concatenate([cells @ columns[:, start:start + 3 * _POSES_PER_PRODUCT]
                                 for start in range(0, 3 * count, 3 * _POSES_PER_PRODUCT)],
                                axis=1).reshape(len(cells), count, 3)
    pos_terms = pos[:, 0, None] * rot[:, 0] + pos[:, 1, None] * rot[:, 1] + pos[:, 2, None] * rot[:, 2]
    local = cell_terms - pos_terms
    return ((np.abs(local[..., 1]) <= half[1]) & (np.abs(local[..., 2]) <= half[2])
            & (local[..., 0] >= -half[0] - tolerance)).T


def contact_summary(scene: Any, parts: WipeParts, normal: np.ndarray) -> tuple[float, bool]:
    """(sponge–table normal force along ``normal`` [3], any other robot geom touching the table) from
    ``data.contact`` and ``mj_contactForce`` of the ``scene``'s model and data (reference for the contact sensors;
    slow)."""
    m, d = scene.model, scene.data
    force6 = np.zeros(6)
    total, arm = 0.0, False
    for i in range(d.ncon):
        contact = d.contact[i]
        pair = {int(contact.geom1), int(contact.geom2)}
        if parts.table_geom not in pair:
            continue
        other = (pair - {parts.table_geom}).pop() if len(pair) == 2 else parts.table_geom
        if other == parts.sponge_geom:
            mujoco.mj_contactForce(m, d, i, force6)
            total += force6[0] * abs(float(contact.frame[:3] @ normal))
        elif parts.is_arm_geom[other]:
            arm = True
    return total, arm


def arm_table_penetration(data: mujoco.MjData, parts: WipeParts) -> float:
    """Deepest penetration (m, >= 0) of a robot geom other than the sponge into the table, now."""
    d = data
    deepest = 0.0
    for i in range(d.ncon):
        contact = d.contact[i]
        g1, g2 = int(contact.geom1), int(contact.geom2)
        if parts.table_geom in (g1, g2) and (parts.is_arm_geom[g1] or parts.is_arm_geom[g2]):
            deepest = max(deepest, -float(contact.dist))
    return deepest


def _undispatched(function: Callable) -> Callable:
    """numpy's C implementation of ``function`` without the ``__array_function__`` dispatch (about 0.25 us per call
    saved in the control loop; the same function on the same arrays), or ``function`` itself where numpy has none."""
    return getattr(function, "_implementation", function)


class WipeSimulation:
    """The wiping task's hook on the simulation core (:class:`~rdmp_gym.envs.servo.ServoSimulation`), and the
    episode's trace.

    Both envs run the core with it: the episodic env along a whole planned path (:func:`simulate_wipe`), the step
    twin one control step per ``step``. Per control step it does only what must happen online: the force
    controller's pressing depth (:class:`~rdmp_gym.envs.controller.ForceAdaptation`, the one home of the admittance
    law) on the servo targets (:meth:`command`), the physics one physics step at a time for :data:`IMPACT_WINDOW`
    after the first sponge contact, to catch the impact (:meth:`substeps`, :meth:`substep`), and a copy of the
    measurements (:meth:`finish`); :meth:`trace` evaluates the rest vectorised.

    Args:
        scene: the scene (its ``model``, ``data`` and the arm's indices), already reset to rest at the first joint
            targets with the table and the cup in place.
        parts: where the task's objects and sensors are in the scene.
        count: control steps of the episode (``T``).
        adaptation: the force controller (reset here).
        dirt: the dirt cells, the table normal and the wear law.
        frame_skip: physics steps per control step.
        normal: the control normal [3] (world) the pressing depth acts along and the wrist force is read along.
        settings: :class:`SimulationSettings`.
        normal_dq: joint motion per metre along the normal, per control step ``[T, n]`` (the plan's; the servo
            targets are ``q - depth * normal_dq``).
        heights: the commanded sponge height above the nominal surface per control step ``[T]`` (m; read at each
            step, so that a step twin may change the steps ahead).
        cup: whether a cup stands on the table (without one its displacement is 0).
    """

    def __init__(self, scene: Any, parts: WipeParts, count: int, adaptation: ForceAdaptation, dirt: DirtField,
                 frame_skip: int, normal: np.ndarray, settings: SimulationSettings | None = None,
                 normal_dq: np.ndarray | None = None, heights: np.ndarray | None = None, *, cup: bool):
        m, d = scene.model, scene.data
        if frame_skip < 1:
            raise ValueError(f"frame_skip: expected an integer >= 1, got {frame_skip!r}")
        ids = scene.actuator_ids
        if not np.all(m.actuator_ctrllimited[ids]):       # MuJoCo clamps the servo targets to ctrlrange
            raise ValueError("scene: the arm actuators must be ctrl-limited to the joint ranges")
        self.scene, self.parts, self.count, self.adaptation, self.dirt = scene, parts, count, adaptation, dirt
        self.cup = cup
        self.frame_skip, self.normal = frame_skip, normal
        self.settings = SimulationSettings() if settings is None else settings
        self.normal_dq = None if normal_dq is None else np.ascontiguousarray(normal_dq)
        self.heights = heights
        self._ctrl_index: slice | np.ndarray = ids
        if np.array_equal(ids, np.arange(ids[0], ids[0] + len(ids))):
            self._ctrl_index = slice(int(ids[0]), int(ids[0]) + len(ids))
        adaptation.reset()
        self._ft_rot = d.site_xmat[parts.ft_site].reshape(3, 3)
        self._wrist = d.sensordata[parts.force_adr]    # a view: the wrist sensor's force [3], updated by every step
        self._rotated = np.empty(3)                     # R @ f, written in place every step
        self._bias = float(wrist_force_world(d, parts) @ normal)
        self._tn = tuple(float(x) for x in np.asarray(dirt.normal, dtype=np.float64))
        self.fine_window = max(1, round(IMPACT_WINDOW / (m.opt.timestep * frame_skip)))
        # One row per control step, copied with a single call: the sensors, qpos, the sponge site's position
        # and the sponge box's pose (the box pose is the one of the step's last kinematics pass).
        self._rows = _RecordLayout(m.nsensordata, m.nq)
        self.record = np.zeros((count, self._rows.width))
        self._sources = (d.sensordata, d.qpos, d.site_xpos[parts.sponge_site], d.geom_xpos[parts.sponge_geom],
                         d.geom_xmat[parts.sponge_geom])
        self._concatenate = _undispatched(np.concatenate)
        self._dot = _undispatched(np.dot)
        self.wrist_force = np.zeros(count)
        self.depth = np.zeros(count)
        self.peak = np.zeros(count)          # per-step peak force while stepping one physics step at a time
        self.fine = np.zeros(count * frame_skip) if self.settings.fine_force else None
        self.obstacle_start = d.qpos[parts.obstacle_qpos:parts.obstacle_qpos + 3].copy()
        ctrl = d.ctrl[self._ctrl_index]      # a view when the arm actuators are consecutive
        self._ctrl = ctrl if np.shares_memory(ctrl, d.ctrl) else None
        self.measured = 0.0
        self.steps = count
        self.table_penetration = 0.0
        self.first_contact = -1
        self._depth = 0.0
        self._top = 0.0
        self._fine_step = -1
        # MuJoCo resets the data (time back to 0) when accelerations blow up: time that fails to advance
        # signals divergence, as do NaN and excessive wrist forces.
        self._last_time = d.time

    # ------------------------------------------------------------------ the hook (StepHook)
    def command(self, k: int, target: np.ndarray) -> None:
        """The pressing depth from the force controller (its admittance law fed the last wrist force and the
        commanded height of step ``k`` above the surface, m) and the servo targets ``target - depth * normal_dq[k]``
        (``[n]`` each)."""
        depth = self.adaptation.update(self.measured, float(self.heights[k]))
        ndq_row = self.normal_dq[k]
        if self._ctrl is None:
            self.scene.data.ctrl[self._ctrl_index] = target - depth * ndq_row
        else:
            mujoco.mju_addScl(self._ctrl, target, ndq_row, -depth)   # q - depth ndq, elementwise as numpy rounds it
        self._depth = depth

    def substeps(self, k: int) -> bool:
        """One physics step at a time within :data:`IMPACT_WINDOW` of the first contact (always with
        ``fine_force``)."""
        if self.fine is not None or (self.first_contact >= 0 and k < self.first_contact + self.fine_window):
            self._top, self._fine_step = 0.0, k
            return True
        return False

    def substep(self, k: int, i: int) -> None:
        """The sponge-table force after physics step ``i`` of control step ``k``: its peak over the step (and every
        value with ``fine_force``)."""
        sensordata, a = self.scene.data.sensordata, self.parts.sponge_contact_adr
        tn0, tn1, tn2 = self._tn
        force = abs(sensordata[a + 1] * tn0 + sensordata[a + 2] * tn1 + sensordata[a + 3] * tn2)
        self._top = max(self._top, force)
        if self.fine is not None:
            self.fine[k * self.frame_skip + i] = force

    def finish(self, k: int) -> bool:
        """Record control step ``k`` (first contact, the wrist force along the normal, the depth, the record row, the
        arm's penetration into the table); True when the simulation diverged (time that fails to advance, NaN or a
        wrist force above the limit)."""
        d, parts = self.scene.data, self.parts
        sensordata, a = d.sensordata, parts.sponge_contact_adr
        if self._fine_step == k:
            self.peak[k] = self._top
        if self.first_contact < 0 and sensordata[a] > 0:
            self.first_contact = k
        dot = self._dot
        measured = self._bias - float(dot(self.normal, dot(self._ft_rot, self._wrist, out=self._rotated)))
        self.measured = measured
        self.wrist_force[k] = measured
        self.depth[k] = self._depth
        self._concatenate(self._sources, out=self.record[k])
        if sensordata[parts.robot_contact_adr] - sensordata[a] > 0.5:
            self.table_penetration = max(self.table_penetration, arm_table_penetration(d, parts))
        now = d.time
        if now <= self._last_time or measured != measured or abs(measured) > self.settings.max_force:
            self.steps = k + 1
            return True
        self._last_time = now
        return False

    def box_pose(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """The sponge box's pose after control step ``k``: position [3] and orientation (row-major) [9] (world)."""
        return self.record[k, self._rows.box_pos], self.record[k, self._rows.box_rot]

    def contact(self, k: int) -> np.ndarray:
        """The sponge-table contact's net force [3] (world, N) after control step ``k``."""
        a = self.parts.sponge_contact_adr
        return self.record[k, a + 1:a + 4]

    def self_penetration(self, k: int) -> float:
        """Deepest penetration (m, >= 0) of the arm into the robot's own body after control step ``k``."""
        deepest = 0.0
        for adr in self.parts.self_contact_adr:
            if self.record[k, adr] > 0:
                deepest = max(deepest, -float(self.record[k, adr + 1]))
        return deepest

    def dirt_left(self, k: int) -> np.ndarray:
        """Dirt left per cell [N] after control step ``k`` (recomputes the episode so far: for video frames)."""
        a = self.parts.sponge_contact_adr
        rows = self._rows
        return _dirt_left(self.dirt, self.record[:, a:a + 4], self.record[:, rows.box_pos],
                          self.record[:, rows.box_rot], self.parts.sponge_half, k)

    def trace(self, upto: int | None = None, wear: tuple[np.ndarray, np.ndarray] | None = None) -> WipeTrace:
        """The episode's :class:`WipeTrace` (its first :attr:`steps` control steps are live), or of its first
        ``upto`` steps; ``wear``: ``(removed [T], dirt left [N])`` worn step by step, instead of the episode's
        wear evaluated here."""
        scene, parts, record, rows, count = self.scene, self.parts, self.record, self._rows, self.count
        settings = self.settings
        diverged = self.steps < count
        steps = self.steps if upto is None else min(self.steps, upto)
        a = parts.sponge_contact_adr
        contact = record[:, a:a + 4]          # found, net force (world)
        box_pos, box_rot = record[:, rows.box_pos], record[:, rows.box_rot]
        table_normal = np.asarray(self.dirt.normal, dtype=np.float64)
        robot_found = record[:, parts.robot_contact_adr]
        self_found_cols = list(parts.self_contact_adr)             # per link of the robot's body: found, distance
        self_dist_cols = [adr + 1 for adr in parts.self_contact_adr]
        self_distance = np.where(record[:, self_found_cols] > 0, -record[:, self_dist_cols], -np.inf)
        self_found = np.isfinite(self_distance).any(axis=1)
        penetration = max(0.0, self.table_penetration, float(np.fmax.reduce(self_distance.ravel())))
        obstacle_found = record[:, parts.obstacle_contact_adr] > 0
        qpos = record[:, rows.qpos]
        obstacle_pos = qpos[:, parts.obstacle_qpos:parts.obstacle_qpos + 3]
        joint_pos = qpos[:, scene.qpos_adr]
        sponge_pos = record[:, rows.site_pos].copy()
        contact_force = np.abs(contact[:, 1:] @ table_normal)
        over = np.flatnonzero(contact_force[:steps] > settings.max_force)
        unstable = diverged or bool(over.size) or not np.isfinite(contact_force[:steps]).all()
        if over.size:
            steps = min(steps, int(over[0]) + 1)
        live = np.arange(count) < steps
        contact_force = np.where(live, np.nan_to_num(contact_force), 0.0)
        arm_contact = live & (robot_found - contact[:, 0] > 0.5)
        lo = scene.joint_lower + settings.limit_margin
        hi = scene.joint_upper - settings.limit_margin
        at_limit = live & np.any((joint_pos < lo) | (joint_pos > hi), axis=1)
        shift = _cup_shift(obstacle_pos, self.obstacle_start,
                           obstacle_found & live if settings.cup_from_touch else None, live)
        if not self.cup:
            shift[:] = 0.0

        removed, left = (_removal(self.dirt, contact_force, box_pos, box_rot, parts.sponge_half, live) if wear is None
                         else wear)
        peak = np.maximum(self.peak, contact_force)
        impact_step = -1
        impact_force = 0.0
        if self.first_contact >= 0:
            window = slice(self.first_contact, min(steps, self.first_contact + self.fine_window))
            impact_step = self.first_contact + int(np.argmax(peak[window]))
            impact_force = float(peak[impact_step])
        wrist_force, depth_trace = self.wrist_force.copy(), self.depth.copy()
        for array in (wrist_force, depth_trace):
            array[~live] = 0.0
        return WipeTrace(contact_force, wrist_force, depth_trace, removed, left, arm_contact, self_found & live,
                         obstacle_found & live, shift, at_limit, sponge_pos, penetration, impact_force, impact_step,
                         self.fine, steps, unstable)


def simulate_wipe(scene: Any, parts: WipeParts, plan: JointTargetPlan, path_height: np.ndarray,
                  adaptation: ForceAdaptation, dirt: DirtField, frame_skip: int,
                  settings: SimulationSettings | None = None,
                  callback: Callable[[int, Callable[[], np.ndarray]], None] | None = None, *, cup: bool) -> WipeTrace:
    """Run a whole joint-target plan from the current simulation state on the simulation core with the hook
    :class:`WipeSimulation`.

    Args:
        scene: the scene (its ``model``, ``data`` and the arm's indices), already reset to rest at ``plan.q[0]`` with
            the table and the cup in place.
        parts: where the task's objects and sensors are in the scene.
        plan: joint targets per control step ([T] steps) and the control normal.
        path_height: commanded sponge height above the nominal surface per control step, [T] (m).
        adaptation: the force controller (reset here).
        dirt: the dirt cells, the table normal and the wear law.
        frame_skip: physics steps per control step.
        settings: :class:`SimulationSettings` (limit margin, force limit, fine force, the cup's displacement).
        callback: called as ``callback(k, dirt_left)`` after control step ``k``; ``dirt_left()`` returns the
            dirt left per cell ``[N]`` so far (e.g. to grab video frames; each call costs a wear evaluation).
        cup: whether a cup stands on the table.
    """
    count = len(plan)
    if path_height.shape != (count,):
        raise ValueError(f"path_height: expected shape ({count},), got {path_height.shape}")
    simulation = WipeSimulation(scene, parts, count, adaptation, dirt, frame_skip, plan.normal, settings,
                                normal_dq=plan.normal_dq, heights=path_height, cup=cup)
    core = ServoSimulation(scene, count, frame_skip, hook=simulation)

    def after(k: int) -> None:
        callback(k, lambda k=k: simulation.dirt_left(k))

    core.run(np.ascontiguousarray(plan.q), None if callback is None else after)
    return simulation.trace()


def _cup_shift(position: np.ndarray, start: np.ndarray, touched: np.ndarray | None, live: np.ndarray) -> np.ndarray:
    """The cup's displacement ``[T]`` (m) from ``start [3]`` given its positions ``[T, 3]``, zero after the live steps;
    with ``touched [T]`` from where it stood before the first touched step, and zero before that step."""
    if touched is None:
        return np.where(live, np.linalg.norm(position - start, axis=1), 0.0)
    first = np.flatnonzero(touched)
    if not first.size:
        return np.zeros(len(position))
    reference = position[first[0] - 1] if first[0] > 0 else start
    after = np.arange(len(position)) >= first[0]
    return np.where(live & after, np.linalg.norm(position - reference, axis=1), 0.0)


@dataclass(frozen=True)
class _RecordLayout:
    """Columns of the per-step record: sensordata, qpos, sponge site position, sponge box pose."""

    sensors: int
    nq: int

    @property
    def width(self) -> int:
        return self.sensors + self.nq + 15

    @property
    def qpos(self) -> slice:
        return slice(self.sensors, self.sensors + self.nq)

    @property
    def site_pos(self) -> slice:
        return slice(self.sensors + self.nq, self.sensors + self.nq + 3)

    @property
    def box_pos(self) -> slice:
        return slice(self.sensors + self.nq + 3, self.sensors + self.nq + 6)

    @property
    def box_rot(self) -> slice:
        return slice(self.sensors + self.nq + 6, self.sensors + self.nq + 15)


def _slide(box_pos: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """Distance [K] the face centre slid along the table (normal component removed) into each step."""
    step = np.diff(box_pos, axis=0, prepend=box_pos[:1])
    step = step - np.outer(step @ normal, normal)
    return np.linalg.norm(step, axis=1)


def _removal(dirt: DirtField, force: np.ndarray, box_pos: np.ndarray, box_rot: np.ndarray, half: np.ndarray,
             live: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(fraction of all dirt removed per step [K], dirt left per cell [N]) of an episode."""
    count, cells = len(force), len(dirt.world)
    if cells == 0:
        return np.zeros(count), np.zeros(0)
    slide = np.where(live, _slide(box_pos, dirt.normal), 0.0)
    rows, cumulative = dirt.wear_steps(np.where(live, force, 0.0), slide, box_pos, box_rot, half)
    cumulative = np.minimum(cumulative, 1.0)                  # only at the steps that remove dirt
    total = _carry_forward(rows, cumulative.sum(axis=1) / cells, count)
    removed = np.diff(total, prepend=0.0)
    return removed, 1.0 - (cumulative[-1] if rows.size else np.zeros(cells))


def _dirt_left(dirt: DirtField, contact: np.ndarray, box_pos: np.ndarray, box_rot: np.ndarray,
               half: np.ndarray, k: int) -> np.ndarray:
    """Dirt left per cell [N] after control step ``k`` (for callbacks; recomputes the episode so far)."""
    force = np.abs(contact[:k + 1, 1:] @ dirt.normal)
    _, left = _removal(dirt, force, box_pos[:k + 1], box_rot[:k + 1], half, np.ones(k + 1, dtype=bool))
    return left
