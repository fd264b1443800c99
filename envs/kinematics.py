"""Batched forward kinematics and site Jacobians of a serial hinge chain, read from an ``MjModel``.

MuJoCo computes kinematics one configuration at a time. The wiping controller needs the kinematics of
a whole path (``B`` ~ 1000 configurations) at once, so this module re-implements MuJoCo's body/joint
composition rule for the hinge chain from the root to a site's body and evaluates it vectorised over
a batch with numpy. Every number comes from the model (``body_pos``, ``body_quat``, ``jnt_pos``,
``jnt_axis``, ``site_pos``, ``site_quat``); the tests check it against ``mj_kinematics``.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

__all__ = ["ChainKinematics", "ChainState"]


def _quat_to_mat(quat: np.ndarray) -> np.ndarray:
    """Rotation matrix [3, 3] of a unit quaternion (w, x, y, z)."""
    mat = np.zeros(9)
    mujoco.mju_quat2Mat(mat, np.asarray(quat, dtype=np.float64))
    return mat.reshape(3, 3)


def _skew(v: np.ndarray) -> np.ndarray:
    """Cross-product matrix [3, 3] of a vector [3]."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


@dataclass(frozen=True)
class ChainState:
    """Kinematics of a batch of configurations.

    Attributes:
        pos: site positions, world frame, [B, 3].
        rot: site orientations (columns = site axes in the world frame), [B, 3, 3].
        axes: joint axes in the world frame, [B, n, 3].
        anchors: joint anchors in the world frame, [B, n, 3].
        body_pos: world positions of the bodies named in ``ChainKinematics(bodies=...)``, [B, k, 3].
        body_rot: their orientations, [B, k, 3, 3].
    """

    pos: np.ndarray
    rot: np.ndarray
    axes: np.ndarray
    anchors: np.ndarray
    body_pos: np.ndarray | None = None
    body_rot: np.ndarray | None = None

    def jacobian(self) -> tuple[np.ndarray, np.ndarray]:
        """Positional and rotational site Jacobians, each [B, 3, n]."""
        jac_rot = np.swapaxes(self.axes, 1, 2)
        lever = self.pos[:, None, :] - self.anchors
        a, b = self.axes, lever
        cross = np.stack([a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1],
                          a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
                          a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]], axis=1)
        jac_pos = cross
        return jac_pos, jac_rot


class ChainKinematics:
    """Vectorised kinematics of the hinge chain that carries ``site`` (all joints from the root).

    Args:
        model: the MuJoCo model; it must not have free/ball joints on the chain and the chain's root
            body must be fixed to the world (a mocap-free, welded base).
        site: name of the site whose pose and Jacobian are computed.
        joints: names of the chain's joints in root-to-tip order; ``None`` takes all joints on the chain.
            Joints on the chain that are not listed are held at ``qpos0``.
        bodies: names of bodies on the chain whose frames ``forward`` also returns (``body_pos``,
            ``body_rot``); ``body_joints[i]`` is the number of active joints that move body ``i``.
    """

    def __init__(self, model: mujoco.MjModel, site: str, joints: tuple[str, ...] | None = None,
                 bodies: tuple[str, ...] = ()):
        site_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, site)
        if site_id < 0:
            raise ValueError(f"site: no site named {site!r} in the model")
        body = int(model.site_bodyid[site_id])
        chain_bodies = []
        while body != 0:
            chain_bodies.append(body)
            body = int(model.body_parentid[body])
        chain_bodies.reverse()
        chain_joints = []
        for b in chain_bodies:
            for j in range(model.body_jntadr[b], model.body_jntadr[b] + model.body_jntnum[b]):
                if model.jnt_type[j] != mujoco.mjtJoint.mjJNT_HINGE:
                    raise ValueError(f"site: joint {model.joint(j).name!r} on the chain is not a hinge")
                chain_joints.append(j)
        names = [model.joint(j).name for j in chain_joints]
        if joints is None:
            joints = tuple(names)
        unknown = [name for name in joints if name not in names]
        if unknown:
            raise ValueError(f"joints: {unknown} are not hinge joints on the chain of site {site!r}")
        if list(joints) != [name for name in names if name in joints]:
            raise ValueError("joints: must be listed in root-to-tip order")
        self.site_id = site_id
        self.joint_names = tuple(joints)
        self.joint_ids = np.array([mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, n) for n in joints])
        self.qpos_adr = model.jnt_qposadr[self.joint_ids].copy()
        self.dof_adr = model.jnt_dofadr[self.joint_ids].copy()
        self.lower = model.jnt_range[self.joint_ids, 0].copy()
        self.upper = model.jnt_range[self.joint_ids, 1].copy()
        body_ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name) for name in bodies]
        if any(b not in chain_bodies for b in body_ids):
            raise ValueError(f"bodies: {bodies} must all be bodies on the chain of site {site!r}")
        self._record = [chain_bodies.index(b) for b in body_ids]
        self.body_joints = np.array([sum(1 for j in self.joint_ids if model.jnt_bodyid[j] in chain_bodies[:i + 1])
                                     for i in self._record], dtype=int)
        # Static description: per body (pos, rot, [(active index or -1, K, K2, jnt_pos, qpos0)]).
        self._bodies = []
        active = {j: i for i, j in enumerate(self.joint_ids)}
        for b in chain_bodies:
            jnts = []
            for j in range(model.body_jntadr[b], model.body_jntadr[b] + model.body_jntnum[b]):
                axis = model.jnt_axis[j] / np.linalg.norm(model.jnt_axis[j])
                k = _skew(axis)
                jnt_pos = model.jnt_pos[j].copy()
                jnts.append((active.get(j, -1), axis, k, k @ k, jnt_pos if np.any(jnt_pos) else None,
                             float(model.qpos0[model.jnt_qposadr[j]])))
            body_pos = model.body_pos[b].copy()
            body_rot = _quat_to_mat(model.body_quat[b])
            self._bodies.append((body_pos if np.any(body_pos) else None,
                                 None if np.allclose(body_rot, np.eye(3), atol=0, rtol=0) else body_rot, jnts))
        self._site_pos = model.site_pos[site_id].copy()
        self._site_rot = _quat_to_mat(model.site_quat[site_id])
        self.n = len(self.joint_ids)

    def forward(self, q: np.ndarray) -> ChainState:
        """Kinematics of a batch of chain configurations ``q`` [B, n] (radians)."""
        q = np.asarray(q, dtype=np.float64)
        if q.ndim != 2 or q.shape[1] != self.n:
            raise ValueError(f"q: expected shape [B, {self.n}], got {q.shape}")
        batch = q.shape[0]
        pos = np.zeros((batch, 3))
        rot = np.broadcast_to(np.eye(3), (batch, 3, 3)).copy()
        axes = np.empty((batch, self.n, 3))
        anchors = np.empty((batch, self.n, 3))

        # rot @ M for rot [B, 3, 3] and a constant M [3, 3] is one gemm on the [3B, 3] view.
        def rmul(r: np.ndarray, m: np.ndarray) -> np.ndarray:
            return (r.reshape(-1, 3) @ m).reshape(batch, 3, 3)

        def rvec(r: np.ndarray, v: np.ndarray) -> np.ndarray:
            return (r.reshape(-1, 3) @ v).reshape(batch, 3)

        # the sines and cosines of all active joints at once (the same numbers as column by column)
        sines, cosines = np.sin(q), np.cos(q)
        fall = 1.0 - cosines
        frames = []
        for body_pos, body_rot, jnts in self._bodies:
            if body_pos is not None:
                pos = pos + rvec(rot, body_pos)
            if body_rot is not None:
                rot = rmul(rot, body_rot)
            for index, axis, k, k2, jnt_pos, qpos0 in jnts:
                has_offset = jnt_pos is not None
                anchor = pos + rvec(rot, jnt_pos) if has_offset else pos
                if index >= 0:
                    axes[:, index] = rvec(rot, axis)
                    anchors[:, index] = anchor
                    s, one_minus_c = sines[:, index, None, None], fall[:, index, None, None]
                else:                                   # a chain joint held at qpos0
                    angle = np.full(batch, qpos0)
                    s, one_minus_c = np.sin(angle)[:, None, None], 1.0 - np.cos(angle)[:, None, None]
                turn = rmul(rot, k)                     # rot + s (rot K) + (1 - c) (rot K^2), in place
                turn *= s
                bend = rmul(rot, k2)
                bend *= one_minus_c
                turn += rot                             # = rot + turn
                turn += bend
                rot = turn
                pos = anchor - rvec(rot, jnt_pos) if has_offset else anchor
            frames.append((pos, rot))
        site_pos = pos + rvec(rot, self._site_pos)
        site_rot = rmul(rot, self._site_rot)
        if not self._record:
            return ChainState(site_pos, site_rot, axes, anchors)
        return ChainState(site_pos, site_rot, axes, anchors,
                          np.stack([frames[i][0] for i in self._record], axis=1),
                          np.stack([frames[i][1] for i in self._record], axis=1))
