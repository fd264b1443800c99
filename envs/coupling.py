"""The coupling term of the step twins: a bounded action shifts a planned tool path through the DMP's transformation
system, and the joint path follows at fixed tool orientation.

:func:`coupling_filter` is the exact discrete response of the transformation system to a coupling held over a control
step; :func:`joint_shift` the damped least-squares joint change for a shift of the tool; :func:`plan_velocity` the
servo feed-forward of a joint path at one step; :func:`coupling_action` and :func:`axis_shift` check a step twin's
action and its ``max_shift``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.linalg import expm

__all__ = ["axis_shift", "coupling_action", "coupling_filter", "joint_shift", "plan_velocity"]

#: Damping (m) of the joint correction's least squares.
_DAMPING = 1e-3


def coupling_filter(omega: float, alpha_z: float, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """``(A [2, 2], B [2])``: the exact discrete step of ``dz = omega (alpha_z (beta_z (0 - y) - z) + c)``,
    ``dy = omega z`` (``beta_z = alpha_z / 4``) over ``dt`` with ``c`` held: ``(y, z)' = A (y, z) + B c``."""
    beta_z = alpha_z / 4.0
    continuous = np.zeros((3, 3))
    continuous[:2, :2] = omega * np.array([[0.0, 1.0], [-alpha_z * beta_z, -alpha_z]])
    continuous[1, 2] = omega
    step = expm(continuous * dt)
    return step[:2, :2], step[:2, 2]


def joint_shift(kinematics: Any, q: np.ndarray, shift: np.ndarray) -> np.ndarray:
    """Joint change ``[n]`` that moves the chain's site by ``shift [3]`` (world, m) at fixed orientation, by damped
    least squares on the Jacobian of ``kinematics`` (a :class:`~rdmp_gym.envs.kinematics.ChainKinematics`) at
    ``q [n]``."""
    jac_pos, jac_rot = kinematics.forward(q[None]).jacobian()
    jac = np.vstack([jac_pos[0], jac_rot[0]])
    rhs = np.r_[shift, np.zeros(3)]
    return np.linalg.solve(jac.T @ jac + _DAMPING**2 * np.eye(len(q)), jac.T @ rhs)


def plan_velocity(q: np.ndarray, k: int, dt: float) -> np.ndarray:
    """Joint velocity ``[n]`` at step ``k`` of a joint path ``q [T, n]``: ``np.gradient`` of the path (as the
    episodic plan's feed-forward), for one step, reading only steps ``k - 1 .. k + 1``."""
    count = len(q)
    if count == 1:
        return np.zeros(q.shape[1])
    if k == 0:
        return (q[1] - q[0]) / dt
    if k == count - 1:
        return (q[k] - q[k - 1]) / dt
    return (q[k + 1] - q[k - 1]) / (2.0 * dt)


def coupling_action(action: Any) -> np.ndarray:
    """A step twin's action as ``[3]`` float64 clipped to [-1, 1]; ValueError for a wrong shape, NaN or inf."""
    try:
        a = np.asarray(action, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise ValueError(f"action: expected a numeric array of shape (3,), got {type(action).__name__}") from error
    if a.shape != (3,):
        raise ValueError(f"action: expected shape (3,), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError("action: contains NaN or infinite values")
    return np.clip(a, -1.0, 1.0)


def axis_shift(max_shift: Any) -> np.ndarray:
    """``max_shift`` (a number or three) as ``[3]`` float64; ValueError unless finite and >= 0."""
    message = f"max_shift: expected a number >= 0 (m) or three, got {max_shift!r}"
    if isinstance(max_shift, bool):
        raise ValueError(message)
    try:
        shift = np.broadcast_to(np.asarray(max_shift, dtype=np.float64), (3,)).copy()
    except (TypeError, ValueError) as error:
        raise ValueError(message) from error
    if not (np.all(np.isfinite(shift)) and np.all(shift >= 0.0)):
        raise ValueError(message)
    return shift
