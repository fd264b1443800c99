"""Unit quaternions ``[..., 4]`` ordered ``(w, x, y, z)`` (scalar first) and the maps a pose DMP needs.

* products and checks: :func:`multiply`, :func:`conjugate`, :func:`check_unit`, :func:`from_matrix`;
* ``q`` and ``-q`` are one orientation: :func:`continuous` picks signs without jumps along a series, :func:`mean`
  is the orientation about which a series stays closest, :func:`angle_between` is sign-blind;
* tangent coordinates: :func:`log_map` and :func:`exp_map` between quaternions and rotation vectors (axis times
  angle, rad), :func:`to_tangent` / :func:`from_tangent` relative to a reference orientation,
  ``q = reference * exp_map(v)``;
* rates: :func:`angular_velocity`, :func:`angular_acceleration` of a series (rad/s, rad/s^2, body frame).

:func:`log_map` returns angles in ``[0, 2 pi]``: a quaternion with ``w < 0`` maps to the far branch, so a series
made :func:`continuous` has continuous tangent coordinates through a half turn (the usual ``[0, pi]`` branch jumps
there). Tangent coordinates stop being smooth only near a full turn from the reference.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from ..validation import as_finite_array

__all__ = ["MAX_TANGENT_ANGLE", "angle_between", "angular_acceleration", "angular_velocity", "check_unit",
           "conjugate", "continuous", "exp_map", "from_matrix", "from_tangent", "log_map", "mean", "multiply",
           "to_tangent"]

MAX_TANGENT_ANGLE = 1.5 * np.pi
"""The largest angle (rad) from the reference that :func:`to_tangent` accepts: beyond it the tangent coordinates
near a full turn would turn small rotations into large jumps."""

_UNIT_TOLERANCE = 1e-2      # a row whose norm differs more from 1 is refused (wrong columns or units), not normalised


def check_unit(q: object, name: str = "q", tolerance: float = _UNIT_TOLERANCE) -> np.ndarray:
    """``q [..., 4]`` as float64, normalised; a ``ValueError`` naming ``name`` and the first bad row where a norm
    differs from 1 by more than ``tolerance`` (a zero row, swapped columns, degrees)."""
    array = as_finite_array(q, name)
    if array.ndim == 0 or array.shape[-1] != 4:
        raise ValueError(f"{name}: expected quaternions [..., 4] (w, x, y, z), got shape {array.shape}")
    norms = np.linalg.norm(array, axis=-1)
    bad = np.abs(norms - 1.0) > tolerance
    if np.any(bad):
        row = np.unravel_index(int(np.argmax(bad)), bad.shape)
        where = "" if not row else f" row {row[0] if len(row) == 1 else row}"
        raise ValueError(f"{name}:{where} has norm {norms[row]:.4g}; expected unit quaternions (w, x, y, z) with "
                         f"norms within {tolerance:g} of 1")
    return array / norms[..., None]


def multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The Hamilton product ``a * b`` of ``[..., 4]`` arrays (broadcast): rotation b, then a, in a's frame."""
    aw, ax, ay, az = np.moveaxis(np.asarray(a, dtype=float), -1, 0)
    bw, bx, by, bz = np.moveaxis(np.asarray(b, dtype=float), -1, 0)
    return np.stack([aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw], axis=-1)


def conjugate(q: np.ndarray) -> np.ndarray:
    """``q*`` ``[..., 4]``: the inverse rotation of a unit quaternion."""
    return np.asarray(q, dtype=float) * np.array([1.0, -1.0, -1.0, -1.0])


def from_matrix(matrix: np.ndarray) -> np.ndarray:
    """Unit quaternions ``[..., 4]`` of rotation matrices ``[..., 3, 3]`` (w >= 0)."""
    matrix = as_finite_array(matrix, "matrix")
    if matrix.ndim < 2 or matrix.shape[-2:] != (3, 3):
        raise ValueError(f"matrix: expected rotation matrices [..., 3, 3], got shape {matrix.shape}")
    xyzw = Rotation.from_matrix(matrix.reshape(-1, 3, 3)).as_quat()
    q = np.concatenate([xyzw[:, 3:], xyzw[:, :3]], axis=1)
    return (q * np.where(q[:, :1] < 0.0, -1.0, 1.0)).reshape(*matrix.shape[:-2], 4)


def continuous(q: np.ndarray) -> np.ndarray:
    """``q [L, 4]`` with signs flipped so that neighbours lie in one hemisphere (``q_k . q_{k+1} >= 0``): the
    same orientations, without the jumps of a recorder that writes ``q`` or ``-q`` at will."""
    q = np.asarray(q, dtype=float)
    flips = np.concatenate([[False], np.sum(q[1:] * q[:-1], axis=1) < 0.0])
    return q * np.where(np.cumsum(flips) % 2 == 1, -1.0, 1.0)[:, None]


def mean(q: np.ndarray) -> np.ndarray:
    """The mean orientation ``[4]`` of a series ``q [L, 4]``: the normalised sum of the :func:`continuous`
    series (the chordal mean when the series stays within a half turn of it); ``ValueError`` for a series whose
    orientations cancel out (it turns all the way round)."""
    total = np.sum(continuous(check_unit(q, "q").reshape(-1, 4)), axis=0)
    size = float(np.linalg.norm(total))
    if size < 1e-3 * q.shape[0]:
        raise ValueError("q: the orientations turn all the way round; no mean orientation to encode them about")
    return total / size


def log_map(q: np.ndarray) -> np.ndarray:
    """Rotation vectors ``[..., 3]`` (axis times angle, rad) of unit quaternions ``[..., 4]``: angle
    ``2 atan2(|(x, y, z)|, w)`` in ``[0, 2 pi]`` (``w < 0``: the far branch, see the module docstring)."""
    q = np.asarray(q, dtype=float)
    vector = q[..., 1:]
    sine = np.linalg.norm(vector, axis=-1)
    angle = 2.0 * np.arctan2(sine, q[..., 0])
    near = (sine < 1e-12) & (q[..., 0] > 0.0)         # angle ~ 2 sine / w: no 0 / 0
    factor = np.where(near, 2.0 / np.where(near, q[..., 0], 1.0), angle / np.maximum(sine, 1e-300))
    return vector * factor[..., None]


def exp_map(v: np.ndarray) -> np.ndarray:
    """Unit quaternions ``[..., 4]`` of rotation vectors ``v [..., 3]`` (rad): ``(cos(|v|/2), sin(|v|/2) v/|v|)``;
    unit norm for any ``v``, continuous in ``v``."""
    v = np.asarray(v, dtype=float)
    angle = np.linalg.norm(v, axis=-1)
    half = 0.5 * angle
    factor = np.where(angle < 1e-8, 0.5 - angle**2 / 48.0, np.sin(half) / np.where(angle < 1e-8, 1.0, angle))
    q = np.concatenate([np.cos(half)[..., None], v * factor[..., None]], axis=-1)
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def to_tangent(q: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """Tangent coordinates ``v [L, 3]`` (rad) of a series ``q [L, 4]`` about ``reference [4]``,
    ``q = reference * exp_map(v)``: continuous along the series whatever the signs of its rows.

    The series is made :func:`continuous` and given the sign that puts its sample nearest to the reference on the
    near branch. ``ValueError`` where it strays more than :data:`MAX_TANGENT_ANGLE` from the reference.
    """
    q = continuous(check_unit(q, "q"))
    relative = multiply(conjugate(check_unit(reference, "reference")), q)
    relative *= np.sign(relative[int(np.argmax(np.abs(relative[:, 0]))), 0]) or 1.0
    furthest = float(np.max(2.0 * np.arctan2(np.linalg.norm(relative[:, 1:], axis=1), relative[:, 0])))
    if furthest > MAX_TANGENT_ANGLE:
        raise ValueError(f"q: the orientation turns {np.degrees(furthest):.0f} deg from the reference orientation; "
                         f"at most {np.degrees(MAX_TANGENT_ANGLE):.0f} deg can be encoded about one reference")
    return log_map(relative)


def from_tangent(v: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """Unit quaternions ``[..., 4]`` of tangent coordinates ``v [..., 3]`` about ``reference [4]``."""
    return multiply(reference, exp_map(v))


def angle_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The rotation angle (rad, ``[0, pi]``) between orientations ``a`` and ``b`` ``[..., 4]``; ``q`` and ``-q``
    are the same orientation."""
    relative = multiply(conjugate(a), b)
    return 2.0 * np.arctan2(np.linalg.norm(relative[..., 1:], axis=-1), np.abs(relative[..., 0]))


def angular_velocity(q: np.ndarray, dt: float) -> np.ndarray:
    """Body-frame angular velocity ``[L - 1, ..., 3]`` (rad/s) between consecutive samples of ``q [L, ..., 4]``
    (every ``dt`` s), each from the rotation that takes one sample to the next (signs of the rows do not matter)."""
    step = multiply(conjugate(q[:-1]), q[1:])
    step *= np.where(step[..., :1] < 0.0, -1.0, 1.0)
    return log_map(step) / dt


def angular_acceleration(q: np.ndarray, dt: float) -> np.ndarray:
    """Angular acceleration ``[L - 2, ..., 3]`` (rad/s^2, body frame; its norm is the world frame's) of
    ``q [L, ..., 4]``."""
    return np.diff(angular_velocity(q, dt), axis=0) / dt
