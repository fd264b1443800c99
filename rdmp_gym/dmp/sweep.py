"""The anchor's travel: a discrete movement of the anchor on which the rhythmic pattern runs.

A rhythmic DMP wipes where its anchor g is. People wipe a large surface by moving the circling hand across
it; the DMP does the same when its anchor follows a smooth discrete path while the pattern runs (the paper
moves the anchor during the motion, Fig. 9, and the pattern follows). :class:`Sweep` is that path: the anchor
rests at its own position until ``times[0]``, passes through K via points (offsets from the anchor) at
``times[1:]`` and rests at the last one from ``times[-1]`` on.

Between the via points the path is the minimum-jerk path through them (Flash & Hogan 1985): a quintic spline,
four times continuously differentiable at the via points, with velocity and acceleration 0 where it leaves
and where it reaches its rest. It is linear in the via points, ``offset(t) = basis(t) @ points``, so a batch
of paths costs one matrix product and the via points can be fitted to a recording by least squares.

Times are unit-tempo time, like the rest of the movement: at tempo 2 the anchor travels twice as fast.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import make_interp_spline

from ..validation import as_finite_array

__all__ = ["Sweep"]



@dataclass(frozen=True)
class Sweep:
    """A minimum-jerk path of the anchor through via points.

    Args:
        times: ``[K + 1]`` strictly increasing times (s, unit tempo, >= 0): the anchor leaves its rest at
            ``times[0]`` and passes via point k at ``times[k + 1]``.
        points: ``[K, d]`` via points, offsets from the anchor (zeros: the anchor stays where it is).
    """

    times: np.ndarray
    points: np.ndarray
    _spline: object = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        times = as_finite_array(self.times, "times", ndim=1)
        points = as_finite_array(self.points, "points", ndim=2)
        if times.size < 2:
            raise ValueError(f"times: expected at least 2 times (a start and one via point), got {times.size}")
        if times[0] < 0.0 or np.any(np.diff(times) <= 0.0):
            raise ValueError("times: expected strictly increasing times >= 0")
        if points.shape[0] != times.size - 1:
            raise ValueError(f"points: expected {times.size - 1} via points (one per time after the first), "
                             f"got {points.shape[0]}")
        values = np.vstack([np.zeros(times.size - 1), np.eye(times.size - 1)])          # [K + 1, K]
        rest = [(1, np.zeros(times.size - 1)), (2, np.zeros(times.size - 1))]   # velocity, acceleration 0
        object.__setattr__(self, "times", times)
        object.__setattr__(self, "points", points)
        object.__setattr__(self, "_spline", make_interp_spline(times, values, k=5, bc_type=(rest, rest)))

    @classmethod
    def uniform(cls, start: float, end: float, n_points: int, n_dims: int) -> Sweep:
        """``n_points`` via points evenly spaced in time from ``start`` to ``end`` (s), all at the anchor."""
        if not isinstance(n_points, (int, np.integer)) or n_points < 1:
            raise ValueError(f"n_points: expected an int >= 1, got {n_points!r}")
        if not isinstance(n_dims, (int, np.integer)) or n_dims < 1:
            raise ValueError(f"n_dims: expected an int >= 1, got {n_dims!r}")
        if not 0.0 <= start < end:
            raise ValueError(f"start, end: expected 0 <= start < end, got {start!r}, {end!r}")
        return cls(np.linspace(start, end, n_points + 1), np.zeros((n_points, n_dims)))

    @property
    def n_points(self) -> int:
        """Number of via points K."""
        return int(self.points.shape[0])

    @property
    def n_dims(self) -> int:
        """Dimensions d of the via points."""
        return int(self.points.shape[1])

    def basis(self, t: np.ndarray, derivative: int = 0) -> np.ndarray:
        """``[T, K]`` weights (or their ``derivative``-th time derivative) of the via points at times ``t [T]``
        (unit tempo): ``offset(t) = basis(t) @ points``; 0 before ``times[0]``, the last point after ``times[-1]``."""
        t = as_finite_array(t, "t", ndim=1)
        inside = (t >= self.times[0]) & (t <= self.times[-1])
        out = self._spline(np.clip(t, self.times[0], self.times[-1]), nu=derivative)
        if derivative:
            out[~inside] = 0.0
        return out

    def offsets(self, t: np.ndarray, points: np.ndarray | None = None, derivative: int = 0) -> np.ndarray:
        """Offsets of the anchor at times ``t [T]``: ``[T, d]`` for this sweep's own points, ``[B, T, d]`` for
        ``points [B, K, d]`` (or their ``derivative``-th time derivative)."""
        basis = self.basis(t, derivative)
        if points is None:
            return basis @ self.points
        points = np.asarray(points, dtype=float)
        if points.ndim != 3 or points.shape[1:] != self.points.shape:
            raise ValueError(f"points: expected shape (B, {self.n_points}, {self.n_dims}), got {points.shape}")
        return np.einsum("tk,bkd->btd", basis, points)

    def with_points(self, points: np.ndarray) -> Sweep:
        """The same timing with other via points ``[K, d]``."""
        return Sweep(self.times, points)

    def to_dict(self) -> dict:
        """Plain-JSON form: ``{"times": [...], "points": [[...], ...]}``."""
        return {"times": self.times.tolist(), "points": self.points.tolist()}

    @classmethod
    def from_dict(cls, data: object) -> Sweep:
        """Read :meth:`to_dict`'s form (errors name the field)."""
        if not isinstance(data, dict) or set(data) != {"times", "points"}:
            raise ValueError("sweep: expected an object with exactly the keys 'times' and 'points'")
        try:
            return cls(np.asarray(data["times"], dtype=float), np.asarray(data["points"], dtype=float))
        except (TypeError, ValueError) as error:
            raise ValueError(f"sweep: {error}") from error
