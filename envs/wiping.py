"""Simulate the sponge along a joint-target plan: contact forces, wiped dirt cells, collisions.

One call runs a whole wiping episode in MuJoCo at the control rate (``frame_skip`` physics steps per
control step). The loop itself does only what must happen online: the wrist-force adaptation of the
pressing depth, the servo targets, the physics, and a copy of the per-step measurements. Everything
else is evaluated afterwards, vectorised over the episode, with the same per-step criteria:

- the sponge–table normal force is the net force of MuJoCo's sponge–table contacts (the model's
  ``sponge_table`` contact sensor, i.e. ``mj_contactForce`` summed over exactly those contacts in C),
  projected on the actual table normal; :func:`contact_summary` recomputes it from ``data.contact``;
- an arm collision is any contact between a robot geom other than the sponge and the table
  (``robot_table`` sensor count minus the sponge's);
- a dirt cell is wiped at the first control step at which the sponge–table force lies in the band
  while the cell is under the sponge's footprint (:func:`cells_under_sponge`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import mujoco
import numpy as np

from .controller import ForceAdaptation, JointTargetPlan
from .scene import WipeScene

__all__ = ["DirtCells", "WipeTrace", "cells_under_sponge", "contact_summary", "simulate_wipe"]


@dataclass(frozen=True)
class DirtCells:
    """Dirt cells on the actual table.

    Attributes:
        world: cell centres on the table surface in the world frame, [N, 3].
        normal: the actual table normal in the world frame, [3].
        force_band: (min, max) sponge–table normal force (N) that wipes.
        depth_tolerance: a cell counts as under the sponge only if the sponge face is within this
            distance (m) of it along the face normal (a tilted sponge touches with one edge only).
    """

    world: np.ndarray
    normal: np.ndarray
    force_band: tuple[float, float] = (5.0, 60.0)
    depth_tolerance: float = 0.003


@dataclass
class WipeTrace:
    """Per-control-step record of a simulated wipe (``T`` control steps, ``N`` cells).

    Attributes:
        contact_force: normal force of the sponge–table contacts, [T] (N).
        wrist_force: bias-corrected wrist force along the nominal table normal, + = pressing, [T] (N).
        depth: commanded pressing depth (preload + adapted offset), [T] (m).
        new_cells: number of cells first wiped at each step, [T].
        arm_contact: a robot geom other than the sponge touches the table, [T].
        at_limit: a controlled joint is within the margin of a limit, [T].
        sponge_pos: sponge face centre (uncompressed, on the hand), [T, 3] (world).
        wiped: final wiped mask, [N].
        steps: number of valid control steps (``T`` unless unstable).
        unstable: the simulation diverged (NaN, MuJoCo's reset on bad accelerations, or a force above
            the limit) at step ``steps - 1``; later entries are zero.
    """

    contact_force: np.ndarray
    wrist_force: np.ndarray
    depth: np.ndarray
    new_cells: np.ndarray
    arm_contact: np.ndarray
    at_limit: np.ndarray
    sponge_pos: np.ndarray
    wiped: np.ndarray
    steps: int
    unstable: bool


def cells_under_sponge(cells: np.ndarray, pos: np.ndarray, rot: np.ndarray, half: np.ndarray,
                       tolerance: float) -> np.ndarray:
    """Which cells lie under the sponge's face, for K sponge poses: bool ``[K, N]``.

    Args:
        cells: cell centres, world frame, [N, 3].
        pos: sponge box centres, [K, 3]; rot: sponge box orientations (row-major 3x3), [K, 9].
        half: the sponge box half sizes [3]; the face is the box side at -x.
        tolerance: how far (m) beyond the face plane a cell may lie and still count.
    """
    k = len(pos)
    rot = rot.reshape(k, 3, 3)
    # local[k, n, :] = R_k^T (c_n - p_k): one gemm for all poses
    local = (cells @ rot.transpose(1, 0, 2).reshape(3, 3 * k)).reshape(len(cells), k, 3).transpose(1, 0, 2)
    local = local - np.einsum("kj,kji->ki", pos, rot)[:, None, :]
    return ((np.abs(local[..., 1]) <= half[1]) & (np.abs(local[..., 2]) <= half[2])
            & (local[..., 0] >= -half[0] - tolerance))


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


def simulate_wipe(
    scene: WipeScene,
    plan: JointTargetPlan,
    path_height: np.ndarray,
    adaptation: ForceAdaptation,
    dirt: DirtCells,
    frame_skip: int,
    limit_margin: float = 0.02,
    max_force: float = 2000.0,
    callback: Callable[[int, np.ndarray], None] | None = None,
) -> WipeTrace:
    """Run the plan from the current simulation state.

    Args:
        scene: the scene, already reset to rest at ``plan.q[0]`` with the table in place.
        plan: joint targets per control step ([T] steps).
        path_height: commanded sponge height above the nominal surface per control step, [T] (m).
        adaptation: the force controller (reset here).
        dirt: the dirt cells, the table normal and the wiping force band.
        frame_skip: physics steps per control step.
        limit_margin: distance to a joint limit (rad) counted as "at the limit".
        max_force: any wrist or contact force above this (N) counts as a diverged simulation.
        callback: called as ``callback(k, wiped)`` after control step ``k`` with the wiped mask ``[N]``
            so far (e.g. to grab video frames); it costs a coverage evaluation per step.
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
    update = adaptation.update
    normal = scene.nominal_normal
    table_normal = np.asarray(dirt.normal, dtype=np.float64)
    ft_rot = d.site_xmat[scene.ft_site]
    sensordata = d.sensordata
    force_adr = scene.force_adr
    bias_n = float(scene.wrist_force_world() @ normal)
    contact_rows = slice(scene.sponge_contact_adr, scene.sponge_contact_adr + 4)
    robot_adr = scene.robot_contact_adr
    qpos_adr: slice | np.ndarray = scene.qpos_adr
    if np.array_equal(qpos_adr, np.arange(qpos_adr[0], qpos_adr[0] + len(qpos_adr))):
        qpos_adr = slice(int(qpos_adr[0]), int(qpos_adr[0]) + len(scene.qpos_adr))
    # wrist force along the normal: n . (R f); with n a world axis that is one row of R
    axis = int(np.argmax(np.abs(normal)))
    row = slice(3 * axis, 3 * axis + 3) if abs(normal[axis]) == 1.0 else None
    sign = float(normal[axis])
    geom_xpos, geom_xmat = d.geom_xpos[scene.sponge_geom], d.geom_xmat[scene.sponge_geom]
    site_xpos = d.site_xpos[scene.sponge_site]
    half = scene.sponge_half
    f_lo, f_hi = dirt.force_band
    cells = dirt.world

    contact = np.zeros((count, 4))        # found, net force (world)
    robot_found = np.zeros(count)
    wrist_force = np.zeros(count)
    depth_trace = np.zeros(count)
    joint_pos = np.zeros((count, len(scene.qpos_adr)))
    sponge_pos = np.zeros((count, 3))
    box_pos = np.zeros((count, 3))
    box_rot = np.zeros((count, 9))
    live_wiped = np.zeros(len(cells), dtype=bool)
    q_all, ndq = plan.q, plan.normal_dq
    step = mujoco.mj_step
    measured = 0.0
    steps = count
    # MuJoCo resets the data (time back to 0) when accelerations blow up: time that fails to advance
    # signals divergence, as do NaN and excessive wrist forces.
    last_time = d.time

    for k in range(count):
        depth = update(measured, path_height[k])
        d.ctrl[ctrl_index] = q_all[k] - depth * ndq[k]
        step(m, d, frame_skip)
        if row is not None:
            measured = bias_n - sign * float(ft_rot[row] @ sensordata[force_adr])
        else:
            measured = bias_n - float(normal @ (ft_rot.reshape(3, 3) @ sensordata[force_adr]))
        wrist_force[k] = measured
        depth_trace[k] = depth
        contact[k] = sensordata[contact_rows]
        robot_found[k] = sensordata[robot_adr]
        joint_pos[k] = d.qpos[qpos_adr]
        sponge_pos[k] = site_xpos
        box_pos[k] = geom_xpos
        box_rot[k] = geom_xmat
        now = d.time
        if now <= last_time or measured != measured or abs(measured) > max_force:
            steps = k + 1
            break
        last_time = now
        if callback is not None:
            force = abs(float(contact[k, 1:] @ table_normal))
            if f_lo <= force <= f_hi:
                live_wiped |= cells_under_sponge(cells, box_pos[k:k + 1], box_rot[k:k + 1], half,
                                                 dirt.depth_tolerance)[0]
            callback(k, live_wiped)

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

    new_cells = np.zeros(count, dtype=np.int64)
    wiped = np.zeros(len(cells), dtype=bool)
    band = np.flatnonzero(live & (contact_force >= f_lo) & (contact_force <= f_hi))
    chunk = max(1, 200_000 // max(1, len(cells)))
    for start in range(0, band.size, chunk):
        rows = band[start:start + chunk]
        under = cells_under_sponge(cells, box_pos[rows], box_rot[rows], half, dirt.depth_tolerance) & ~wiped
        hit = under.any(axis=0)
        if hit.any():
            first = rows[np.argmax(under[:, hit], axis=0)]
            np.add.at(new_cells, first, 1)
            wiped |= hit
    for array in (wrist_force, depth_trace):
        array[~live] = 0.0
    return WipeTrace(contact_force, wrist_force, depth_trace, new_cells, arm_contact, at_limit,
                     sponge_pos, wiped, steps, unstable)
