"""Keeping the hand clear of the cup: a clearance term on the commanded sponge path.

The sponge is held beside the hand, and the fingers reach about 15 cm beyond the sponge's centre. A pattern that
wipes the edge of a patch next to a cup can therefore knock the cup with the fingers while the sponge itself stays
clear of it: the sponge's path alone does not show the collision. :class:`CupClearance` checks the planned posture
of every control step (forward kinematics of the joint path) and, where a part of the hand comes closer than
``margin`` to the cup's side below its top, pushes the sponge's path away from the cup in the table plane by
what is missing, spread smoothly over the neighbouring steps. It is a coupling term of the executed primitive,
as an obstacle term is (see :mod:`rdmp_gym.dmp.coupling`): the learned parameters are unchanged, the executed path
differs only near the cup.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import mujoco
import numpy as np
from scipy.ndimage import gaussian_filter1d

__all__ = ["Cup", "CupClearance", "HandPoints"]

class HandPoints:
    """World points on the hand's geoms for a joint path: the corners, edge and face centres of each geom's
    bounding box (27 per geom), by forward kinematics on a private copy of the model's data."""

    def __init__(self, model: mujoco.MjModel, qpos_adr: np.ndarray, geoms: Sequence[str]):
        ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, name) for name in geoms]
        missing = [name for name, i in zip(geoms, ids, strict=True) if i < 0]
        if missing:
            raise ValueError(f"geoms: {missing} are not geoms of the model")
        self.names = tuple(geoms)
        self.model, self.qpos_adr, self.ids = model, np.asarray(qpos_adr), np.array(ids)
        self._data = mujoco.MjData(model)
        unit = np.array(np.meshgrid(*[[-1.0, 0.0, 1.0]] * 3, indexing="ij")).reshape(3, -1).T   # [27, 3]
        aabb = model.geom_aabb[self.ids]                                                       # [G, 6]
        self._local = aabb[:, None, :3] + unit[None] * aabb[:, None, 3:]                       # [G, 27, 3]

    def __call__(self, q: np.ndarray) -> np.ndarray:
        """World points ``[T, G * 27, 3]`` of the geoms at joint positions ``q [T, n]``."""
        q = np.asarray(q, dtype=np.float64)
        out = np.empty((len(q), *self._local.shape[:2], 3))
        data = self._data
        for t, row in enumerate(q):
            data.qpos[self.qpos_adr] = row
            mujoco.mj_kinematics(self.model, data)
            rot = data.geom_xmat[self.ids].reshape(-1, 3, 3)
            out[t] = data.geom_xpos[self.ids][:, None] + np.einsum("gij,gkj->gki", rot, self._local)
        return out.reshape(len(q), -1, 3)

    def gaps(self, q: np.ndarray, cup: Cup) -> np.ndarray:
        """``[T, G]``: per geom, the smallest horizontal gap (m) between its points below ``cup``'s top and the
        cup's side at joint positions ``q [T, n]`` (negative: inside the cup's footprint; inf: all above it)."""
        points = self(q).reshape(len(q), len(self.ids), -1, 3)
        return (cup.horizontal(points)[1] - cup.radius).min(axis=-1)


@dataclass(frozen=True)
class Cup:
    """A standing cylinder: centre of its base ``[3]`` (world, m), radius and top height (world z, m)."""

    base: np.ndarray
    radius: float
    top: float

    def horizontal(self, points: np.ndarray, headroom: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """``(offsets [..., 2], distances [...])`` of world ``points [..., 3]`` from the cup's axis in the
        horizontal plane; the distance is inf for a point higher than the top plus ``headroom`` (m)."""
        offsets = points[..., :2] - self.base[:2]
        distances = np.linalg.norm(offsets, axis=-1)
        distances[points[..., 2] > self.top + headroom] = np.inf
        return offsets, distances


@dataclass(frozen=True)
class CupClearance:
    """Push the commanded sponge path away from the cup where the planned posture brings the hand within
    ``margin`` (m) of the cup's side.

    Attributes:
        margin: smallest horizontal gap (m) between the hand's points below the cup's top (plus ``margin``) and
            the cup's side.
        smoothing: standard deviation (s) of the Gaussian that spreads each control step's push over its
            neighbours; the spread push is then scaled by one factor so that it gives every step at least what
            it needs along its own direction (so the push is as smooth as the Gaussian).
        iterations: plan, check and push rounds (the posture changes a little with the pushed path).
        max_push: largest push (m) of one round at any step (where the needs disagree, e.g. with the hand
            above the cup's centre, the round's push is this at most).
    """

    margin: float = 0.01
    smoothing: float = 0.25
    iterations: int = 3
    max_push: float = 0.05

    def __post_init__(self) -> None:
        for name in ("margin", "smoothing", "max_push"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value) or value <= 0:
                raise ValueError(f"{name}: expected a finite number > 0, got {value!r}")
        if isinstance(self.iterations, bool) or not isinstance(self.iterations, int) or self.iterations < 1:
            raise ValueError(f"iterations: expected an int >= 1, got {self.iterations!r}")

    def push(self, points: np.ndarray, cup: Cup, rotation: np.ndarray, dt: float) -> np.ndarray:
        """The smooth push ``[T, 3]`` (control frame, zero along the table normal) that the hand's world points
        ``points [T, K, 3]`` (one row per control step of ``dt`` s) need to keep ``margin`` from ``cup``;
        ``rotation [3, 3]``: the control frame's axes (columns) in the world."""
        rel, dist = cup.horizontal(points, self.margin)
        nearest = np.argmin(dist, axis=1)
        steps = np.arange(len(points))
        gap = dist[steps, nearest]
        need = np.minimum(np.maximum(0.0, cup.radius + self.margin - gap), self.max_push)
        if not np.any(need > 0):
            return np.zeros((len(points), 3))
        away = rel[steps, nearest] / np.maximum(gap, 1e-9)[:, None]
        world = np.zeros((len(points), 3))
        world[:, :2] = need[:, None] * away
        raw = world @ rotation
        raw[:, 2] = 0.0
        spread = gaussian_filter1d(raw, self.smoothing / dt, axis=0, mode="nearest")
        needed = need > 0
        reach = np.sum(spread[needed] * raw[needed], axis=1) / need[needed] ** 2   # spread push along each need
        largest = float(np.max(np.linalg.norm(spread, axis=1)))
        return spread * min(1.0 / max(float(np.min(reach)), 1e-12), self.max_push / largest)

    def apply(self, path: np.ndarray, solution, solve: Callable, hand: HandPoints, cup: Cup,
              rotation: np.ndarray, dt: float) -> tuple[np.ndarray, object, float]:
        """``(path [T, 3], its IK solution, largest total push (m))``: ``path`` (control frame) with the pushes
        of up to ``iterations`` rounds, each planned with ``solve(path)`` (the IK ``solution`` of ``path`` is
        reused for the first check)."""
        total = np.zeros_like(path)
        for _ in range(self.iterations):
            push = self.push(hand(solution.q), cup, rotation, dt)
            if not np.any(push):
                break
            total += push
            solution = solve(path + total)
        return path + total, solution, float(np.max(np.linalg.norm(total, axis=1)))
