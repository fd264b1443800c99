"""Simulate the sponge along a joint-target plan: contact forces, dirt wear, collisions, the obstacle.

One call runs a whole wiping episode in MuJoCo at the control rate (``frame_skip`` physics steps per
control step). The loop does only what must happen online: the wrist-force adaptation of the pressing
depth, the servo targets, the physics and a copy of the per-step measurements. For 0.2 s after the
first sponge contact it steps the physics one step at a time to catch the touchdown's peak force (the
impact). Everything else is evaluated afterwards, vectorised over the episode:

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
  :mod:`rdmp_gym.envs.arena`); for both the deepest penetration is recorded;
- the obstacle: whether the arm touches it (sensor ``arm_obstacle``) and how far it has moved.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import mujoco
import numpy as np

from .controller import ForceAdaptation, JointTargetPlan
from .scene import WipeScene

__all__ = ["IMPACT_WINDOW", "DirtField", "WipeTrace", "arm_table_penetration", "cells_under_sponge",
           "contact_summary", "simulate_wipe"]

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


def contact_summary(scene: WipeScene, normal: np.ndarray) -> tuple[float, bool]:
    """(sponge–table normal force along ``normal`` [3], any other robot geom touching the table) from
    ``data.contact`` and ``mj_contactForce`` (reference for the contact sensors; slow)."""
    m, d = scene.model, scene.data
    force6 = np.zeros(6)
    total, arm = 0.0, False
    for i in range(d.ncon):
        contact = d.contact[i]
        pair = {int(contact.geom1), int(contact.geom2)}
        if scene.table_geom not in pair:
            continue
        other = (pair - {scene.table_geom}).pop() if len(pair) == 2 else scene.table_geom
        if other == scene.sponge_geom:
            mujoco.mj_contactForce(m, d, i, force6)
            total += force6[0] * abs(float(contact.frame[:3] @ normal))
        elif scene.is_arm_geom[other]:
            arm = True
    return total, arm


def arm_table_penetration(scene: WipeScene) -> float:
    """Deepest penetration (m, >= 0) of a robot geom other than the sponge into the table, now."""
    d = scene.data
    deepest = 0.0
    for i in range(d.ncon):
        contact = d.contact[i]
        g1, g2 = int(contact.geom1), int(contact.geom2)
        if scene.table_geom in (g1, g2) and (scene.is_arm_geom[g1] or scene.is_arm_geom[g2]):
            deepest = max(deepest, -float(contact.dist))
    return deepest


def _undispatched(function: Callable) -> Callable:
    """numpy's C implementation of ``function`` without the ``__array_function__`` dispatch (about 0.25 us per call
    saved in the control loop; the same function on the same arrays), or ``function`` itself where numpy has none."""
    return getattr(function, "_implementation", function)


def simulate_wipe(
    scene: WipeScene,
    plan: JointTargetPlan,
    path_height: np.ndarray,
    adaptation: ForceAdaptation,
    dirt: DirtField,
    frame_skip: int,
    limit_margin: float = 0.02,
    max_force: float = 2000.0,
    callback: Callable[[int, Callable[[], np.ndarray]], None] | None = None,
    fine_force: bool = False,
    cup_from_touch: bool = False,
) -> WipeTrace:
    """Run the plan from the current simulation state.

    Args:
        scene: the scene, already reset to rest at ``plan.q[0]`` with the table and obstacle in place.
        plan: joint targets per control step ([T] steps) and the control normal.
        path_height: commanded sponge height above the nominal surface per control step, [T] (m).
        adaptation: the force controller (reset here).
        dirt: the dirt cells, the table normal and the wear law.
        frame_skip: physics steps per control step.
        limit_margin: distance to a joint limit (rad) counted as "at the limit".
        max_force: any wrist or contact force above this (N) counts as a diverged simulation.
        callback: called as ``callback(k, dirt_left)`` after control step ``k``; ``dirt_left()`` returns the
            dirt left per cell ``[N]`` so far (e.g. to grab video frames; each call costs a wear evaluation).
        fine_force: also record the sponge–table force at every physics step (``trace.fine_force``).
        cup_from_touch: measure the cup's displacement from where it stood just before the robot first touched
            it (zero before): a cup that settles untouched has not moved (else from where it was placed).
    """
    m, d = scene.model, scene.data
    count = len(plan)
    if path_height.shape != (count,):
        raise ValueError(f"path_height: expected shape ({count},), got {path_height.shape}")
    if frame_skip < 1:
        raise ValueError(f"frame_skip: expected an integer >= 1, got {frame_skip!r}")
    ids = scene.actuator_ids
    if not np.all(m.actuator_ctrllimited[ids]):       # MuJoCo clamps the servo targets to ctrlrange
        raise ValueError("scene: the arm actuators must be ctrl-limited to the joint ranges")
    ctrl_index: slice | np.ndarray = ids
    if np.array_equal(ids, np.arange(ids[0], ids[0] + len(ids))):
        ctrl_index = slice(int(ids[0]), int(ids[0]) + len(ids))
    adaptation.reset()
    normal = plan.normal
    table_normal = np.asarray(dirt.normal, dtype=np.float64)
    ft_rot = d.site_xmat[scene.ft_site].reshape(3, 3)
    sensordata = d.sensordata
    wrist = sensordata[scene.force_adr]      # a view: the wrist sensor's force [3], updated by every step
    rotated = np.empty(3)                    # R @ f, written in place every step
    bias_n = float(scene.wrist_force_world() @ normal)
    a = scene.sponge_contact_adr
    robot_adr = scene.robot_contact_adr
    self_found_cols = list(scene.self_contact_adr)                # per link of the robot's body: found, distance
    self_dist_cols = [adr + 1 for adr in scene.self_contact_adr]
    half = scene.sponge_half
    tn0, tn1, tn2 = (float(x) for x in table_normal)
    fine_window = max(1, round(IMPACT_WINDOW / (m.opt.timestep * frame_skip)))

    # One row per control step, copied with a single call: the sensors, qpos, the sponge site's position
    # and the sponge box's pose (the box pose is the one of the step's last kinematics pass).
    sensors = m.nsensordata
    rows = _RecordLayout(sensors, m.nq)
    record = np.zeros((count, rows.width))
    sources = (sensordata, d.qpos, d.site_xpos[scene.sponge_site], d.geom_xpos[scene.sponge_geom],
               d.geom_xmat[scene.sponge_geom])
    concatenate = _undispatched(np.concatenate)
    contact = record[:, a:a + 4]          # found, net force (world)
    box_pos, box_rot = record[:, rows.box_pos], record[:, rows.box_rot]
    wrist_force = np.zeros(count)
    depth_trace = np.zeros(count)
    peak = np.zeros(count)                # per-step peak force while stepping one physics step at a time
    fine = np.zeros(count * frame_skip) if fine_force else None
    obstacle_qpos = slice(scene.obstacle_qpos, scene.obstacle_qpos + 3)
    obstacle_start = d.qpos[obstacle_qpos].copy()
    ctrl = d.ctrl[ctrl_index]             # a view when the arm actuators are consecutive
    if not np.shares_memory(ctrl, d.ctrl):
        ctrl = None
    q_rows, ndq_rows = list(np.ascontiguousarray(plan.q)), list(np.ascontiguousarray(plan.normal_dq))
    add_scaled, dot = mujoco.mju_addScl, _undispatched(np.dot)   # q - depth ndq, elementwise as numpy rounds it
    # the admittance law of ForceAdaptation.update, inlined (same operations in the same order)
    law = adaptation.settings
    adapt = law.enabled
    engage = adaptation.engagement(path_height).tolist()
    alpha, dt, preload = adaptation.alpha, adaptation.dt, adaptation.preload
    gain, target, max_rate = law.gain, law.target_force, law.max_rate
    min_offset, max_offset = law.min_offset, law.max_offset
    filtered, offset = adaptation.force, adaptation.offset
    learn = getattr(adaptation, "learn", None)    # a learned depth profile on top (force_learning)
    step = mujoco.mj_step
    measured = 0.0
    steps = count
    table_penetration = 0.0
    first_contact = -1
    # MuJoCo resets the data (time back to 0) when accelerations blow up: time that fails to advance
    # signals divergence, as do NaN and excessive wrist forces.
    last_time = d.time

    for k in range(count):
        filtered += alpha * (measured - filtered)
        if adapt:
            rate = gain * (target - filtered) * engage[k]
            # min(max_rate, max(-max_rate, rate)) and the same for the offset, as conditional expressions that
            # return what the builtins return (the first argument unless the second is strictly beyond it)
            rate = rate if rate > -max_rate else -max_rate
            rate = rate if rate < max_rate else max_rate
            offset = offset + rate * dt
            offset = offset if offset > min_offset else min_offset
            offset = offset if offset < max_offset else max_offset
        depth = preload + offset
        if learn is not None:
            depth += learn(filtered, engage[k])
        if ctrl is None:
            d.ctrl[ctrl_index] = q_rows[k] - depth * ndq_rows[k]
        else:
            add_scaled(ctrl, q_rows[k], ndq_rows[k], -depth)
        if fine is not None or (first_contact >= 0 and k < first_contact + fine_window):
            top = 0.0
            for i in range(frame_skip):
                step(m, d)
                force = abs(sensordata[a + 1] * tn0 + sensordata[a + 2] * tn1 + sensordata[a + 3] * tn2)
                top = max(top, force)
                if fine is not None:
                    fine[k * frame_skip + i] = force
            peak[k] = top
        else:
            step(m, d, frame_skip)
        if first_contact < 0 and sensordata[a] > 0:
            first_contact = k
        measured = bias_n - float(dot(normal, dot(ft_rot, wrist, out=rotated)))   # = normal @ (R @ f)
        wrist_force[k] = measured
        depth_trace[k] = depth
        concatenate(sources, out=record[k])
        if sensordata[robot_adr] - sensordata[a] > 0.5:
            table_penetration = max(table_penetration, arm_table_penetration(scene))
        now = d.time
        if now <= last_time or measured != measured or abs(measured) > max_force:
            steps = k + 1
            break
        last_time = now
        if callback is not None:
            callback(k, lambda k=k: _dirt_left(dirt, contact, box_pos, box_rot, half, k))
    adaptation.force, adaptation.offset = filtered, offset

    robot_found = record[:, robot_adr]
    self_distance = np.where(record[:, self_found_cols] > 0, -record[:, self_dist_cols], -np.inf)
    self_found = np.isfinite(self_distance).any(axis=1)
    penetration = max(0.0, table_penetration, float(np.fmax.reduce(self_distance.ravel())))
    obstacle_found = record[:, scene.obstacle_contact_adr] > 0
    qpos = record[:, rows.qpos]
    obstacle_pos = qpos[:, obstacle_qpos]
    joint_pos = qpos[:, scene.qpos_adr]
    sponge_pos = record[:, rows.site_pos].copy()
    contact_force = np.abs(contact[:, 1:] @ table_normal)
    over = np.flatnonzero(contact_force[:steps] > max_force)
    unstable = steps < count or bool(over.size) or not np.isfinite(contact_force[:steps]).all()
    if over.size:
        steps = min(steps, int(over[0]) + 1)
    live = np.arange(count) < steps
    contact_force = np.where(live, np.nan_to_num(contact_force), 0.0)
    arm_contact = live & (robot_found - contact[:, 0] > 0.5)
    lo = scene.joint_lower + limit_margin
    hi = scene.joint_upper - limit_margin
    at_limit = live & np.any((joint_pos < lo) | (joint_pos > hi), axis=1)
    shift = _cup_shift(obstacle_pos, obstacle_start, obstacle_found & live if cup_from_touch else None, live)
    if scene.obstacle_xy is None:
        shift[:] = 0.0

    removed, left = _removal(dirt, contact_force, box_pos, box_rot, half, live)
    peak = np.maximum(peak, contact_force)
    impact_step = -1
    impact_force = 0.0
    if first_contact >= 0:
        window = slice(first_contact, min(steps, first_contact + fine_window))
        impact_step = first_contact + int(np.argmax(peak[window]))
        impact_force = float(peak[impact_step])
    for array in (wrist_force, depth_trace):
        array[~live] = 0.0
    return WipeTrace(contact_force, wrist_force, depth_trace, removed, left, arm_contact, self_found & live,
                     obstacle_found & live, shift, at_limit, sponge_pos, penetration, impact_force, impact_step,
                     fine, steps, unstable)


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
