"""Obstacle avoidance as a coupling term of the transformation system (Hoffmann et al. 2009; Park et al. 2008).

The steering term of Hoffmann et al. (ICRA 2009) turns the velocity away from a point obstacle ``o``:

    p(y, v) = gamma * R v * theta * exp(-beta * theta)

``theta`` is the angle between the velocity ``v`` and the direction ``o - y`` to the obstacle, and ``R``
rotates by +90 degrees about ``k = (o - y) x v``, so ``R v = k/|k| x v`` lies in the plane of ``v`` and
``o - y``, is perpendicular to ``v`` and points away from the obstacle. Beyond the original, an optional
Gaussian distance window ``exp(-|o - y|^2 / (2 lambda^2))`` (the idea of Park et al.'s dynamic potential:
act only near the obstacle) keeps a periodic movement unchanged away from it.

``p`` is an acceleration (m/s^2). In the DMP's transformation system (4) it enters as the coupling term
``c = p / Omega^2`` (:meth:`rdmp_gym.DMPStepper.step` converts an object with an ``acceleration`` method).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .validation import as_finite_array, check_positive

__all__ = ["ObstacleAvoidance", "avoiding_rollout"]


@dataclass(frozen=True)
class ObstacleAvoidance:
    """Hoffmann et al.'s (2009) steering term around a point obstacle.

    Args:
        obstacle: ``[k]`` obstacle position (k = 2 or 3) in the coordinates of ``dims``.
        gamma: gain (1/s; Hoffmann et al. use 1000 with their time scale).
        beta: angular decay (1/rad; Hoffmann et al. use 20/pi).
        distance_scale: ``lambda`` (m) of the distance window; ``None`` for the original term (no window).
        dims: which ``k`` of the DMP's d dimensions the obstacle lives in (default: the first k).
    """

    obstacle: np.ndarray
    gamma: float = 1000.0
    beta: float = 20.0 / np.pi
    distance_scale: float | None = None
    dims: tuple[int, ...] | None = None

    def __post_init__(self) -> None:
        obstacle = as_finite_array(self.obstacle, "obstacle", ndim=1)
        if obstacle.size not in (2, 3):
            raise ValueError(f"obstacle: expected 2 or 3 coordinates, got {obstacle.size}")
        object.__setattr__(self, "obstacle", obstacle)
        object.__setattr__(self, "gamma", check_positive(self.gamma, "gamma"))
        object.__setattr__(self, "beta", check_positive(self.beta, "beta"))
        if self.distance_scale is not None:
            object.__setattr__(self, "distance_scale", check_positive(self.distance_scale, "distance_scale"))
        dims = tuple(range(obstacle.size)) if self.dims is None else tuple(int(i) for i in self.dims)
        if len(dims) != obstacle.size or len(set(dims)) != len(dims) or min(dims) < 0:
            raise ValueError(f"dims: expected {obstacle.size} distinct non-negative indices, got {self.dims!r}")
        object.__setattr__(self, "dims", dims)

    def _steer(self, y: np.ndarray, v: np.ndarray) -> np.ndarray:
        """``p`` in the obstacle's coordinates: ``y, v [..., k]`` -> ``[..., k]``."""
        to_obstacle = self.obstacle - y
        y3 = np.zeros((*y.shape[:-1], 3))
        v3, o3 = y3.copy(), y3.copy()
        v3[..., : y.shape[-1]], o3[..., : y.shape[-1]] = v, to_obstacle
        axis = np.cross(o3, v3)
        axis_norm = np.linalg.norm(axis, axis=-1, keepdims=True)
        distance = np.linalg.norm(o3, axis=-1, keepdims=True)
        speed = np.linalg.norm(v3, axis=-1, keepdims=True)
        cosine = np.sum(o3 * v3, axis=-1, keepdims=True) / np.maximum(distance * speed, 1e-300)
        theta = np.arccos(np.clip(cosine, -1.0, 1.0))
        turned = np.cross(axis / np.maximum(axis_norm, 1e-300), v3)      # R v
        p = self.gamma * turned * theta * np.exp(-self.beta * theta)
        if self.distance_scale is not None:
            p = p * np.exp(-0.5 * (distance / self.distance_scale) ** 2)
        p = np.where(axis_norm > 1e-12 * np.maximum(distance * speed, 1e-300), p, 0.0)   # v = 0 or collinear
        return p[..., : y.shape[-1]]

    def acceleration(self, y: np.ndarray, yd: np.ndarray) -> np.ndarray:
        """The steering acceleration ``[d]`` (m/s^2) at position ``y [d]`` and velocity ``yd [d]``; 0 in the
        dimensions the obstacle does not live in."""
        y = as_finite_array(y, "y", ndim=1)
        yd = as_finite_array(yd, "yd", ndim=1)
        if y.shape != yd.shape or max(self.dims) >= y.size:
            raise ValueError(f"y: expected matching positions and velocities with more than {max(self.dims)} "
                             f"dimensions, got {y.shape} and {yd.shape}")
        out = np.zeros_like(y)
        out[list(self.dims)] = self._steer(y[list(self.dims)], yd[list(self.dims)])
        return out


def avoiding_rollout(dmp, t: np.ndarray, obstacles: ObstacleAvoidance | list[ObstacleAvoidance], *,
                     smoothing: float = 0.0, stop_at: float | None = None, **start_kwargs
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Roll ``dmp`` out online with the steering terms of ``obstacles`` (the no-learning baseline).

    Args:
        dmp: a :class:`rdmp_gym.RhythmicDMP`.
        t: ``[T]`` evenly spaced times from the start.
        obstacles: one or several :class:`ObstacleAvoidance` terms (their accelerations add).
        smoothing: time constant (s) of a first-order low-pass on the coupling term (0: none, Hoffmann et
            al.'s term as is). The raw term switches on and off within a few centimetres and, against the stiff
            spring of (4), makes sharp accelerations; 0.1 s cuts the squared jerk by about 10x (see README).
        stop_at: request the stop at this time (a DMP with an ending).
        start_kwargs: passed to :meth:`RhythmicDMP.start` (transient, y0, yd0, anchor, tempo, start_blend).
    Returns:
        positions and velocities, each ``[T, d]``.
    """
    from .validation import check_time_grid

    t = check_time_grid(t, "t")
    terms = [obstacles] if hasattr(obstacles, "acceleration") else list(obstacles)
    if not terms or not all(callable(getattr(term, "acceleration", None)) for term in terms):
        raise TypeError("obstacles: expected one or more terms with an acceleration(y, yd) method "
                        "(e.g. ObstacleAvoidance)")
    if not (np.isfinite(smoothing) and smoothing >= 0.0):
        raise ValueError(f"smoothing: expected a time constant >= 0, got {smoothing!r}")
    stepper = dmp.start(float((t[-1] - t[0]) / (t.size - 1)), **start_kwargs)
    share = 1.0 if smoothing == 0.0 else 1.0 - np.exp(-stepper.dt / smoothing)
    coupling = np.zeros(dmp.n_dims)
    positions, velocities = np.empty((t.size, dmp.n_dims)), np.empty((t.size, dmp.n_dims))
    positions[0], velocities[0] = stepper.state
    stop_step = None if stop_at is None else round(float(stop_at) / stepper.dt)
    for i in range(1, t.size):
        if i - 1 == stop_step:
            stepper.request_stop()
        y, yd = stepper.state
        acceleration = sum(term.acceleration(y, yd) for term in terms)
        coupling += share * (acceleration / stepper.omega**2 - coupling)
        positions[i], velocities[i] = stepper.step(coupling)
    return positions, velocities
