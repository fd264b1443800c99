"""Batched differential inverse kinematics for a whole task-space path of the sponge.

Task (5 rows per configuration): the sponge face centre (3 position rows) and the sponge's face normal
kept anti-parallel to the table normal (2 rotation rows about the table's tangent axes; the yaw about
the normal is left free). Redundancy (10 joints) is resolved by a weighted damped least-squares step
with a posture task in its null space; joint limits are enforced by projection after every step.

All configurations of a path are solved together (vectorised), first on a coarse subsample of the
path, then refined on every point from the interpolated coarse solution; the result also carries the
joint direction that moves the sponge along the table normal at fixed orientation, which the force
controller uses to shift the pressing depth online without another IK solve.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
from scipy.interpolate import CubicSpline

from .kinematics import ChainKinematics, ChainState

__all__ = ["BodyClearance", "IKResult", "IKSettings", "PathIK"]


@dataclass(frozen=True)
class IKResult:
    """Joint solution of a path of ``T`` points.

    Attributes:
        q: joint positions, [T, n] (radians).
        normal_dq: joint motion per metre of sponge motion along the table normal, [T, n].
        pos_error: remaining position error norm per point, [T] (metres).
        rot_error: remaining angle between the sponge normal and the target normal per point, [T] (rad).
    """

    q: np.ndarray
    normal_dq: np.ndarray
    pos_error: np.ndarray
    rot_error: np.ndarray


def _tangent_basis(normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors [3] orthogonal to ``normal`` and to each other."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(normal[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    t1 = helper - normal * (helper @ normal)
    t1 /= np.linalg.norm(t1)
    return t1, np.cross(normal, t1)


class BodyClearance:
    """Clearance of arm capsules from a box of the robot's body, and its joint gradient.

    Each capsule's segment is sampled at ``samples`` points; a point's clearance is its distance to the
    box minus the capsule radius (negative inside). The box and the capsules hang on the same chain, so
    the joints that carry both (the first ``kinematics.body_joints[0]``) do not change the clearance.

    Args:
        model: the MuJoCo model the chain was read from.
        kinematics: the chain, built with ``bodies=(box body, capsule body, ...)`` in that order.
        box: name of the box geom (on the first recorded body).
        capsules: names of capsule geoms, one per further recorded body, in the same order.
        samples: points per capsule segment.
    """

    def __init__(self, model: mujoco.MjModel, kinematics: ChainKinematics, box: str,
                 capsules: tuple[str, ...], samples: int = 5):
        if len(kinematics.body_joints) != len(capsules) + 1:
            raise ValueError("kinematics: expected bodies=(box body, one body per capsule)")
        box_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, box)
        if box_id < 0 or model.geom_type[box_id] != mujoco.mjtGeom.mjGEOM_BOX:
            raise ValueError(f"box: no box geom named {box!r}")
        self.box_pos = model.geom_pos[box_id].copy()
        mat = np.zeros(9)
        mujoco.mju_quat2Mat(mat, model.geom_quat[box_id])
        self.box_rot = mat.reshape(3, 3).copy()
        self.box_half = model.geom_size[box_id].copy()
        fractions = np.linspace(-1.0, 1.0, samples)
        points, radii = [], []
        for name in capsules:
            gid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, name)
            if gid < 0 or model.geom_type[gid] != mujoco.mjtGeom.mjGEOM_CAPSULE:
                raise ValueError(f"capsules: no capsule geom named {name!r}")
            mujoco.mju_quat2Mat(mat, model.geom_quat[gid])
            axis = mat.reshape(3, 3)[:, 2] * model.geom_size[gid, 1]
            points.append(model.geom_pos[gid] + fractions[:, None] * axis)       # body frame, [samples, 3]
            radii.append(model.geom_size[gid, 0])
        self.points = np.stack(points)                                           # [c, samples, 3]
        self.radii = np.array(radii)
        self.kin = kinematics
        self.shared = int(kinematics.body_joints[0])

    def evaluate(self, state: ChainState, gradient: bool = True) -> tuple[np.ndarray, np.ndarray | None]:
        """Clearance (m) [B, c * samples] and (if ``gradient``) its gradient in the joints
        [B, c * samples, n] at ``state``."""
        box_rot = state.body_rot[:, 0] @ self.box_rot                                   # [B, 3, 3]
        box_pos = state.body_pos[:, 0] + state.body_rot[:, 0] @ self.box_pos            # [B, 3]
        clearance, gradients = [], []
        for c, (points, radius) in enumerate(zip(self.points, self.radii, strict=True)):
            world = state.body_pos[:, c + 1, None] + np.einsum("bij,sj->bsi", state.body_rot[:, c + 1], points)
            local = np.einsum("bji,bsj->bsi", box_rot, world - box_pos[:, None])       # box frame [B, s, 3]
            outside = local - np.clip(local, -self.box_half, self.box_half)
            out_norm = np.linalg.norm(outside, axis=2)
            depth = self.box_half - np.abs(local)                                       # > 0 on every axis inside
            is_out = out_norm > 1e-9
            distance = np.where(is_out, out_norm, -np.min(depth, axis=2))
            clearance.append(distance - radius)
            if not gradient:
                continue
            face = np.argmin(depth, axis=2)
            inside_dir = np.where(np.arange(3) == face[..., None], np.sign(local), 0.0)
            direction = np.where(is_out[..., None], outside / np.maximum(out_norm, 1e-9)[..., None], inside_dir)
            normal = np.einsum("bij,bsj->bsi", box_rot, direction)                      # world [B, s, 3]
            count = int(self.kin.body_joints[c + 1])
            lever = world[:, :, None, :] - state.anchors[:, None, :count]               # [B, s, k, 3]
            # d(distance)/dq_j = n . (a_j x (p - o_j)) = a_j . ((p - o_j) x n)
            grad = np.einsum("bkx,bskx->bsk", state.axes[:, :count], np.cross(lever, normal[:, :, None, :]))
            grad[:, :, :self.shared] = 0.0
            full = np.zeros((*grad.shape[:2], self.kin.n))
            full[:, :, :count] = grad
            gradients.append(full)
        return np.concatenate(clearance, axis=1), np.concatenate(gradients, axis=1) if gradient else None


@dataclass(frozen=True)
class IKSettings:
    """How :class:`PathIK` iterates.

    Attributes:
        damping: damping factor lambda of the least-squares step (> 0).
        limit_margin: distance kept from every joint limit (radians).
        nullspace_gain: fraction of the posture error corrected per iteration.
        limit_zone: width (rad) of the band inside each limit from which the null-space task pushes
            joints back towards the interior.
        limit_gain: fraction of the intrusion into that band corrected per iteration.
        tolerance: after ``min_iterations``, the coarse pass stops when the position errors (m) or the
            joint updates (rad) of all its points are below this (and the angle errors below ``rot_tolerance``).
        rot_tolerance: angle error (rad) below which the coarse pass may stop (1e-3 rad = 0.06 deg).
        clearance_margin: clearance (m) the arm keeps from the body (with a :class:`BodyClearance`).
        clearance_gain: fraction of the clearance deficit corrected per iteration.
    """

    damping: float = 0.01
    limit_margin: float = 0.01
    nullspace_gain: float = 0.1
    limit_zone: float = 0.15
    limit_gain: float = 0.5
    tolerance: float = 1e-4
    rot_tolerance: float = 1e-3
    clearance_margin: float = 0.01
    clearance_gain: float = 1.0

    def __post_init__(self) -> None:
        if not self.damping > 0:
            raise ValueError("damping: expected a positive number")


class PathIK:
    """Damped least-squares IK of the sponge site along a path, vectorised over the path.

    Args:
        kinematics: the arm chain; its site is the (uncompressed) sponge face centre and the site's
            +x axis is the sponge's outward "up" axis (the face normal is -x).
        posture: joint configuration [n] preferred in the null space of the task.
        joint_weights: per-joint mobility [n] in (0, 1] (a small value makes a joint move less).
        clearance: optional arm-to-body clearance; a path whose solution comes closer than
            ``settings.clearance_margin`` (m) to the body is solved again with a null-space task that pushes the
            arm out to the margin (paths that keep clear are solved without it, unchanged).
        settings: how it iterates (:class:`IKSettings`; default its defaults).
    """

    def __init__(self, kinematics: ChainKinematics, posture: np.ndarray, joint_weights: np.ndarray,
                 clearance: BodyClearance | None = None, settings: IKSettings | None = None):
        settings = IKSettings() if settings is None else settings
        n = kinematics.n
        posture = np.asarray(posture, dtype=np.float64)
        joint_weights = np.asarray(joint_weights, dtype=np.float64)
        if posture.shape != (n,):
            raise ValueError(f"posture: expected shape ({n},), got {posture.shape}")
        if joint_weights.shape != (n,) or np.any(joint_weights <= 0):
            raise ValueError(f"joint_weights: expected {n} positive numbers")
        self.kin = kinematics
        self.lower = kinematics.lower + settings.limit_margin
        self.upper = kinematics.upper - settings.limit_margin
        self.posture = np.clip(posture, self.lower, self.upper)
        self.inv_weight = joint_weights
        self.damping2 = settings.damping**2
        self.nullspace_gain = settings.nullspace_gain
        self.tolerance = settings.tolerance
        self.rot_tolerance = settings.rot_tolerance
        self.zone_lower = kinematics.lower + settings.limit_zone
        self.zone_upper = kinematics.upper - settings.limit_zone
        self.limit_gain = settings.limit_gain
        self.clearance = clearance
        self.clearance_margin = settings.clearance_margin
        self.clearance_gain = settings.clearance_gain

    def _linearise(self, q: np.ndarray, targets: np.ndarray, normal: np.ndarray, basis: np.ndarray,
                   rot_weight: np.ndarray, blocked: np.ndarray | None, state: ChainState | None = None,
                   errors: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray | None,
                                                 np.ndarray | None]:
        """Task error and weighted Jacobians at ``q`` [B, n]: (error [B, 5], jac [B, 5, n], jw = W^-1 J^T
        [B, n, 5], A = J W^-1 J^T + lambda^2 I [B, 5, 5], pos_err [B], rot_err [B]); the last two are None
        unless ``errors``."""
        state = self.kin.forward(q) if state is None else state
        jac_pos, jac_rot = state.jacobian()
        up = state.rot[:, :, 0]
        e_pos = targets - state.pos
        r = np.stack([up[:, 1] * normal[2] - up[:, 2] * normal[1], up[:, 2] * normal[0] - up[:, 0] * normal[2],
                      up[:, 0] * normal[1] - up[:, 1] * normal[0]], axis=1)             # np.cross(up, normal)
        error = np.concatenate([e_pos, (r @ basis.T) * rot_weight[:, None]], axis=1)      # [B, 5]
        jac_r = np.einsum("kj,bjn->bkn", basis, jac_rot) * rot_weight[:, None, None]
        jac = np.concatenate([jac_pos, jac_r], axis=1)                                   # [B, 5, n]
        inv_weight = np.broadcast_to(self.inv_weight, q.shape)
        if blocked is not None:
            inv_weight = np.where(blocked, 1e-4 * inv_weight, inv_weight)
        jw = np.swapaxes(jac, 1, 2) * inv_weight[:, :, None]                    # W^-1 J^T [B, n, 5]
        a = jac @ jw
        a[:, range(5), range(5)] += self.damping2
        if not errors:
            return error, jac, jw, a, None, None
        cos_angle = np.clip(up @ normal, -1.0, 1.0)
        return error, jac, jw, a, np.linalg.norm(e_pos, axis=1), np.arccos(cos_angle)

    def _step(self, q: np.ndarray, targets: np.ndarray, normal: np.ndarray, basis: np.ndarray,
              rot_weight: np.ndarray, blocked: np.ndarray | None = None, avoid: bool = False, errors: bool = True
              ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None, np.ndarray]:
        """One DLS update of ``q`` [B, n] with the null-space posture and limit task.

        ``blocked`` [B, n] marks joints held at a limit (they get almost no mobility). Returns
        (q_new, pos_err [B], rot_err [B], blocked_new [B, n]); the errors are those at ``q`` (None unless
        ``errors``).
        """
        state = self.kin.forward(q)
        error, jac, jw, a, pos_err, rot_err = self._linearise(q, targets, normal, basis, rot_weight, blocked, state,
                                                              errors)
        v = self.nullspace_gain * (self.posture - q)                               # [B, n]
        v += self.limit_gain * (np.maximum(0.0, self.zone_lower - q) - np.maximum(0.0, q - self.zone_upper))
        if avoid:
            v += self._push_out(state)
        if blocked is not None:
            v = np.where(blocked, 0.0, v)
        rhs = error - np.einsum("bkn,bn->bk", jac, v)
        step = np.einsum("bnk,bk->bn", jw, np.linalg.solve(a, rhs[..., None])[..., 0])
        step = step + v
        step = np.clip(step, -0.5, 0.5)
        q_free = q + step
        q_new = np.clip(q_free, self.lower, self.upper)
        blocked_new = (q_free < self.lower) | (q_free > self.upper)
        if blocked is not None:
            blocked_new |= blocked & (q_new != q_free)
        return q_new, pos_err, rot_err, blocked_new

    def _push_out(self, state: ChainState) -> np.ndarray:
        """Joint motion [B, n] that raises every sampled clearance below the margin by ``clearance_gain``
        of its deficit (minimum weighted norm per point, summed over the points)."""
        clearance, grad = self.clearance.evaluate(state)                           # [B, p], [B, p, n]
        deficit = np.maximum(0.0, self.clearance_margin - clearance)
        weighted = grad * self.inv_weight
        scale = self.clearance_gain * deficit / (np.einsum("bpn,bpn->bp", weighted, grad) + 1e-9)
        return np.einsum("bp,bpn->bn", scale, weighted)

    def min_clearance(self, q: np.ndarray) -> np.ndarray:
        """Smallest arm-to-body clearance (m) per configuration of ``q`` [B, n], [B] (inf without a body)."""
        if self.clearance is None:
            return np.full(len(q), np.inf)
        return self.clearance.evaluate(self.kin.forward(q), gradient=False)[0].min(axis=1)

    def solve(self, targets: np.ndarray, normal: np.ndarray, rot_weight: np.ndarray | None = None,
              q_init: np.ndarray | None = None,
              stride: int = 10, coarse_iterations: int = 60, fine_iterations: int = 1,
              min_iterations: int = 6) -> IKResult:
        """Solve the IK for a path.

        Args:
            targets: sponge face centre positions in the world frame, [T, 3].
            normal: table normal in the world frame, [3] (the sponge face is pressed against it).
            rot_weight: weight in (0, 1] of the orientation rows per point, [T] (default ones); a
                small weight lets the sponge tilt where flatness matters less (high above the table).
            q_init: start configuration [n] for every point (default: the posture).
            stride: subsampling of the coarse pass.
            coarse_iterations: maximum DLS iterations on the subsampled path.
            fine_iterations: DLS iterations on the full path (from the interpolated coarse solution).
            min_iterations: DLS iterations on the subsampled path before the stopping test.
        """
        result, clearance = self._solve(targets, normal, rot_weight, q_init, stride, coarse_iterations,
                                        fine_iterations, min_iterations, avoid=False)
        if clearance < self.clearance_margin:
            # the clearance task converges more slowly than the sponge task: iterate the coarse pass longer
            result, _ = self._solve(targets, normal, rot_weight, q_init, stride, coarse_iterations,
                                    fine_iterations, max(min_iterations, coarse_iterations // 2), avoid=True)
        return result

    def _solve(self, targets: np.ndarray, normal: np.ndarray, rot_weight: np.ndarray | None,
               q_init: np.ndarray | None, stride: int, coarse_iterations: int, fine_iterations: int,
               min_iterations: int, avoid: bool) -> tuple[IKResult, float]:
        """:meth:`solve` with (``avoid``) or without the clearance task; also the path's smallest
        arm-to-body clearance (m; inf without a body)."""
        targets = np.asarray(targets, dtype=np.float64)
        if targets.ndim != 2 or targets.shape[1] != 3 or len(targets) == 0:
            raise ValueError(f"targets: expected shape [T, 3], got {targets.shape}")
        normal = np.asarray(normal, dtype=np.float64)
        normal = normal / np.linalg.norm(normal)
        basis = np.stack(_tangent_basis(normal))
        count = len(targets)
        rot_weight = np.ones(count) if rot_weight is None else np.asarray(rot_weight, dtype=np.float64)
        if rot_weight.shape != (count,) or np.any(rot_weight <= 0):
            raise ValueError(f"rot_weight: expected {count} positive numbers")
        start = self.posture if q_init is None else np.clip(np.asarray(q_init, np.float64), self.lower, self.upper)
        knots = np.unique(np.r_[np.arange(0, count, max(1, stride)), count - 1])
        q = np.broadcast_to(start, (len(knots), self.kin.n)).copy()
        blocked = None
        knot_targets, knot_weight = targets[knots], rot_weight[knots]
        for iteration in range(coarse_iterations):
            q_old = q
            test = iteration + 1 >= min_iterations           # the errors are needed for the stopping test only
            q, pos_err, rot_err, blocked = self._step(q, knot_targets, normal, basis, knot_weight, blocked, avoid,
                                                    errors=test)
            if test and (
                    (pos_err.max() < self.tolerance and rot_err.max() < self.rot_tolerance)
                    or np.max(np.abs(q - q_old)) < self.tolerance):
                break
        if len(knots) < count:
            index = np.arange(count)
            # a cubic spline, not straight lines, through the coarse solution: the joint path has no
            # velocity kinks at the knots (which showed up as 20 rad/s² spikes in the joint acceleration)
            q = CubicSpline(knots, q, axis=0)(index) if len(knots) > 2 else np.stack(
                [np.interp(index, knots, q[:, j]) for j in range(self.kin.n)], axis=1)
            q = np.clip(q, self.lower, self.upper)
        # The fine pass treats every joint as free (limits still enforced by projection): a "blocked" flag
        # that switches between neighbouring points would make the joint path jump there.
        for _ in range(fine_iterations):
            q, *_ = self._step(q, targets, normal, basis, rot_weight, None, avoid, errors=False)
        state = self.kin.forward(q)
        _, _, jw, a, pos_err, rot_err = self._linearise(q, targets, normal, basis, rot_weight, None, state)
        unit = np.zeros((count, 5, 1))
        unit[:, :3, 0] = normal
        normal_dq = np.einsum("bnk,bk->bn", jw, np.linalg.solve(a, unit)[..., 0])
        clearance = np.inf if self.clearance is None else float(self.clearance.evaluate(state, gradient=False)[0].min())
        return IKResult(q=q, normal_dq=normal_dq, pos_error=pos_err, rot_error=rot_err), clearance
