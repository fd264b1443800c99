"""Simulate the sponge along a joint-target plan: contact forces, wiped dirt cells, collisions.

One call runs a whole wiping episode in MuJoCo at the control rate (``frame_skip`` physics steps per
control step). At every control step it reads, from MuJoCo's contact list and constraint forces, the
normal force of the real sponge–table contacts, marks the dirt cells under the sponge's footprint as
wiped when that force lies in the band, and records arm–environment contacts, joint-limit proximity and
the bias-corrected wrist force that drives the force adaptation.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import mujoco
import numpy as np

from .controller import ForceAdaptation, JointTargetPlan
from .scene import WipeScene

__all__ = ["DirtCells", "WipeTrace", "simulate_wipe"]


@dataclass(frozen=True)
class DirtCells:
    """Dirt cells on the actual table.

    Attributes:
        world: cell centres on the table surface in the world frame, [N, 3].
        force_band: (min, max) sponge–table normal force (N) that wipes.
        depth_tolerance: a cell counts as under the sponge only if the sponge face is within this
            distance (m) of it along the face normal (a tilted sponge touches with one edge only).
    """

    world: np.ndarray
    force_band: tuple[float, float] = (5.0, 60.0)
    depth_tolerance: float = 0.003


@dataclass
class WipeTrace:
    """Per-control-step record of a simulated wipe (``T`` control steps, ``N`` cells).

    Attributes:
        contact_force: summed normal force of the sponge–table contacts, [T] (N).
        wrist_force: bias-corrected wrist force along the nominal table normal, + = pressing, [T] (N).
        depth: commanded pressing depth (preload + adapted offset), [T] (m).
        new_cells: number of cells first wiped at each step, [T].
        arm_contact: any robot geom other than the sponge touches the environment, [T].
        at_limit: any controlled joint is within the margin of a limit, [T].
        sponge_pos: sponge face centre (uncompressed, on the hand), [T, 3] (world).
        wiped: final wiped mask, [N].
        steps: number of control steps simulated (``T`` unless unstable).
        unstable: the simulation diverged (NaN, MuJoCo reset warning or kN forces) at step ``steps - 1``.
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
        dirt: the dirt cells and the wiping force band.
        frame_skip: physics steps per control step.
        limit_margin: distance to a joint limit (rad) counted as "at the limit".
        max_force: any wrist or contact force above this (N) counts as a diverged simulation.
        callback: called as ``callback(k, wiped)`` after control step ``k`` with the current wiped
            mask ``[N]`` (e.g. to grab video frames).
    """
    m, d = scene.model, scene.data
    count = len(plan)
    if path_height.shape != (count,):
        raise ValueError(f"path_height: expected shape ({count},), got {path_height.shape}")
    if frame_skip < 1:
        raise ValueError(f"frame_skip: expected an integer >= 1, got {frame_skip!r}")
    adaptation.reset()
    update = adaptation.update
    normal = scene.nominal_normal
    ft_rot = d.site_xmat[scene.ft_site]
    force_adr = scene.force_adr
    bias_n = float(scene.wrist_force_world() @ normal)
    ids = scene.actuator_ids
    ctrl_index: slice | np.ndarray = ids
    if np.array_equal(ids, np.arange(ids[0], ids[0] + len(ids))):
        ctrl_index = slice(int(ids[0]), int(ids[0]) + len(ids))
    # Servo targets are clamped to ctrlrange (= joint range) by MuJoCo itself.
    if not np.all(m.actuator_ctrllimited[ids]):
        raise ValueError("scene: the arm actuators must be ctrl-limited to the joint ranges")
    qpos_adr = scene.qpos_adr
    # Geom kinds: 1 sponge, 2 table, 4 other robot geom; a contact's kinds OR-ed: 3 = sponge-table.
    kind = np.zeros(m.ngeom, dtype=np.int64)
    kind[scene.is_arm_geom] = 4
    kind[scene.sponge_geom] = 1
    kind[scene.table_geom] = 2
    elliptic = m.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC
    force6 = np.zeros(6)
    cells = dirt.world
    wiped = np.zeros(len(cells), dtype=bool)
    f_lo, f_hi = dirt.force_band
    half_y, half_z = scene.sponge_half[1], scene.sponge_half[2]
    face_limit = -scene.sponge_half[0] - dirt.depth_tolerance
    geom_xpos, geom_xmat = d.geom_xpos[scene.sponge_geom], d.geom_xmat[scene.sponge_geom]
    site_xpos = d.site_xpos[scene.sponge_site]
    sensordata = d.sensordata

    contact_force = np.zeros(count)
    wrist_force = np.zeros(count)
    depth_trace = np.zeros(count)
    new_cells = np.zeros(count, dtype=np.int64)
    arm_contact = np.zeros(count, dtype=bool)
    joint_pos = np.zeros((count, len(qpos_adr)))
    sponge_pos = np.zeros((count, 3))
    measured = 0.0
    steps = count
    unstable = False
    q_all, ndq = plan.q, plan.normal_dq
    step = mujoco.mj_step
    # MuJoCo resets the data (time back to 0) when the accelerations blow up: a time that fails to
    # advance is the divergence signal, together with NaN or excessive forces.
    last_time = d.time

    for k in range(count):
        depth = update(measured, path_height[k])
        d.ctrl[ctrl_index] = q_all[k] - depth * ndq[k]
        step(m, d, frame_skip)

        measured = bias_n - float(normal @ (ft_rot.reshape(3, 3) @ sensordata[force_adr]))
        total = 0.0
        if d.ncon:
            contact = d.contact
            codes = kind[contact.geom]
            joined = codes[:, 0] | codes[:, 1]
            pair = joined == 3
            if elliptic:
                total = float(d.efc_force[contact.efc_address[pair]].sum())
            else:
                for i in np.flatnonzero(pair):
                    mujoco.mj_contactForce(m, d, int(i), force6)
                    total += force6[0]
            arm_contact[k] = joined.max() >= 4
        joint_pos[k] = d.qpos[qpos_adr]
        contact_force[k] = total
        wrist_force[k] = measured
        depth_trace[k] = depth
        sponge_pos[k] = site_xpos
        if f_lo <= total <= f_hi:
            local = (cells - geom_xpos) @ geom_xmat.reshape(3, 3)
            under = (np.abs(local[:, 1]) <= half_y) & (np.abs(local[:, 2]) <= half_z) & (local[:, 0] >= face_limit)
            fresh = under & ~wiped
            n_fresh = int(np.count_nonzero(fresh))
            if n_fresh:
                wiped |= fresh
                new_cells[k] = n_fresh
        now = d.time
        if now <= last_time or measured != measured or abs(measured) > max_force or total > max_force:
            steps, unstable = k + 1, True
            break
        last_time = now
        if callback is not None:
            callback(k, wiped)

    lo = scene.joint_lower + limit_margin
    hi = scene.joint_upper - limit_margin
    at_limit = np.any((joint_pos < lo) | (joint_pos > hi), axis=1)
    at_limit[steps:] = False
    return WipeTrace(contact_force, wrist_force, depth_trace, new_cells, arm_contact, at_limit,
                     sponge_pos, wiped, steps, unstable)
