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

A point steering term on the tool's centre cannot avoid an obstacle with a volume (a cup that the sponge and
the hand must pass). :class:`LiftOver` treats the obstacle as an upright cylinder standing on the plane
``z = 0`` (radius inflated by the tool's horizontal reach) and lifts the movement over it: the coupling shifts
the equilibrium of the height's spring by a smooth height field

    L(y, t) = gate(t) * lift * (1 - s((rho(y) - radius - reach) / ramp)),     p_z = k L,

``rho`` the horizontal distance of ``y`` from the cylinder's axis, ``s`` the minimum-jerk step on [0, 1],
``k = alpha_z beta_z Omega^2`` the DMP's spring (so the path rises by ``L``, filtered by the critically damped
spring), and ``gate`` a minimum-jerk rise from the start and fall before a given time (the approach), so that
the periodic pattern after it is the DMP's own. That lift is conservative: it raises the path by the obstacle's
full height even where the free movement already passes high. :class:`AdaptiveLift` lifts only by what is
missing: it keeps a copy of the shift it has caused (the spring's response to its own past coupling; the
transformation system is linear), so it knows the free movement's height ``y_z - s`` and its rate, and raises
the equilibrium by ``gate(t) (1 - s(...))`` (the footprint of ``L``) times a smooth maximum of 0 and
``top + clearance - (free height predicted lead seconds ahead)``.
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass

import numpy as np

from ..validation import as_finite_array, check_positive, check_time_grid

__all__ = ["AdaptiveLift", "LiftOver", "ObstacleAvoidance", "avoiding_rollout", "minimum_jerk_step",
           "spring_stiffness"]


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


def minimum_jerk_step(x: np.ndarray) -> np.ndarray:
    """The minimum-jerk step ``[...]`` from 0 (``x <= 0``) to 1 (``x >= 1``): ``10x^3 - 15x^4 + 6x^5``."""
    x = np.clip(x, 0.0, 1.0)
    return x**3 * (10.0 - 15.0 * x + 6.0 * x**2)


def spring_stiffness(dmp, tempo: float = 1.0) -> float:
    """``alpha_z beta_z Omega^2`` (1/s^2) of ``dmp`` run at ``tempo``: a coupling acceleration ``k L`` moves the
    spring's equilibrium of (4) by ``L``."""
    omega = dmp.canonical.omega * check_positive(tempo, "tempo")
    return float(dmp.alpha_z * (dmp.alpha_z / 4.0) * omega**2)


@dataclass(frozen=True)
class LiftOver:
    """Lift the movement over an upright cylinder (a cup) standing on the plane ``z = 0``; see the module.

    Args:
        centre: ``[2]`` the cylinder's axis in the plane (coordinates ``dims[:2]``, m).
        top: height of the cylinder's top above the plane (m).
        radius: the cylinder's radius (m).
        reach: horizontal reach of the tool around the moving point (m; e.g. the sponge's half diagonal).
        clearance: height kept above the top (m): the lift is ``top + clearance``.
        ramp: horizontal distance (m) beyond ``radius + reach`` over which the lift fades to 0.
        stiffness: ``k`` (1/s^2), the DMP's spring (:func:`spring_stiffness`).
        window: ``(rise, hold, release)`` (s): the lift rises (minimum jerk) over ``[0, rise]`` and falls over
            ``[hold, release]``; ``None``: no gate (the lift acts at all times).
        dims: which DMP dimensions are the plane's two axes and the height (default ``(0, 1, 2)``).
    """

    centre: np.ndarray
    top: float
    radius: float
    reach: float
    stiffness: float
    clearance: float = 0.01
    ramp: float = 0.1
    window: tuple[float, float, float] | None = None
    dims: tuple[int, int, int] = (0, 1, 2)

    def __post_init__(self) -> None:
        centre = as_finite_array(self.centre, "centre", ndim=1)
        if centre.size != 2:
            raise ValueError(f"centre: expected 2 coordinates, got {centre.size}")
        object.__setattr__(self, "centre", centre)
        for name in ("top", "radius", "stiffness", "ramp"):
            object.__setattr__(self, name, check_positive(getattr(self, name), name))
        for name in ("reach", "clearance"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)) \
                    or not np.isfinite(value) or value < 0:
                raise ValueError(f"{name}: expected a finite number >= 0, got {value!r}")
            object.__setattr__(self, name, float(value))
        if self.window is not None:
            window = as_finite_array(self.window, "window", ndim=1)
            if window.size != 3 or not (0.0 < window[0] and window[1] < window[2] and window[0] <= window[1]):
                raise ValueError(f"window: expected (rise, hold, release) with 0 < rise <= hold < release, "
                                 f"got {self.window!r}")
            object.__setattr__(self, "window", tuple(float(w) for w in window))
        dims = tuple(int(i) for i in self.dims)
        if len(dims) != 3 or len(set(dims)) != 3 or min(dims) < 0:
            raise ValueError(f"dims: expected 3 distinct non-negative indices, got {self.dims!r}")
        object.__setattr__(self, "dims", dims)

    @property
    def lift(self) -> float:
        """The full lift (m): ``top + clearance``."""
        return self.top + self.clearance

    def gate(self, time: float | np.ndarray) -> np.ndarray:
        """The time gate in [0, 1] at ``time`` (s; any shape)."""
        time = np.asarray(time, dtype=np.float64)
        if self.window is None:
            return np.ones_like(time)
        rise, hold, release = self.window
        return minimum_jerk_step(time / rise) * (1.0 - minimum_jerk_step((time - hold) / (release - hold)))

    def height(self, y: np.ndarray) -> np.ndarray:
        """The ungated lift ``[...]`` (m) at positions ``y [..., d]``."""
        y = np.asarray(y, dtype=np.float64)
        rho = np.linalg.norm(y[..., list(self.dims[:2])] - self.centre, axis=-1)
        return self.lift * (1.0 - minimum_jerk_step((rho - self.radius - self.reach) / self.ramp))

    def clearance_of(self, y: np.ndarray) -> np.ndarray:
        """Signed distance ``[...]`` (m) of the tool (a disc of radius ``reach`` at height ``y_z``) from the
        cylinder at positions ``y [..., d]``: the horizontal gap where it is beside the cylinder, else the
        height above the top (negative: inside)."""
        y = np.asarray(y, dtype=np.float64)
        rho = np.linalg.norm(y[..., list(self.dims[:2])] - self.centre, axis=-1)
        return np.maximum(rho - self.radius - self.reach, y[..., self.dims[2]] - self.top)

    def acceleration(self, y: np.ndarray, yd: np.ndarray, time: float | None = None) -> np.ndarray:
        """The lifting acceleration ``[d]`` (m/s^2; only in the height dimension) at position ``y [d]`` (velocity
        ``yd [d]`` unused) and ``time`` (s since the start; required with a ``window``)."""
        y = as_finite_array(y, "y", ndim=1)
        yd = as_finite_array(yd, "yd", ndim=1)
        if y.shape != yd.shape or max(self.dims) >= y.size:
            raise ValueError(f"y: expected matching positions and velocities with more than {max(self.dims)} "
                             f"dimensions, got {y.shape} and {yd.shape}")
        if self.window is not None:
            if time is None or not np.isfinite(time):
                raise ValueError(f"time: a LiftOver with a window needs the finite time, got {time!r}")
        out = np.zeros_like(y)
        gate = 1.0 if self.window is None else float(self.gate(time))
        if gate > 0.0:
            out[self.dims[2]] = self.stiffness * gate * float(self.height(y))
        return out


class AdaptiveLift:
    """Lift over the volume of a :class:`LiftOver` only as far as the free movement needs (see the module).

    The term is stateful (call :meth:`reset` before reusing it) and must be called once per integration step with
    non-decreasing ``time``, as :func:`avoiding_rollout` does. Its copy of the shift assumes the DMP's critically
    damped spring (``beta_z = alpha_z / 4``, so the damping is ``2 sqrt(k)``).

    Args:
        volume: the obstacle, its footprint, gate and the DMP's stiffness ``k``; the height to keep over the
            footprint is its ``top + clearance``.
        lead: how far ahead (s) the free height is predicted from its rate (the spring's lag, about
            ``2 / sqrt(k)``).
        width: width (m) of the smooth maximum ``(x + sqrt(x^2 + width^2)) / 2`` (no kink where the need starts).
    """

    def __init__(self, volume: LiftOver, lead: float = 0.3, width: float = 0.01):
        if not isinstance(volume, LiftOver):
            raise TypeError(f"volume: expected a LiftOver, got {type(volume).__name__}")
        if isinstance(lead, bool) or not isinstance(lead, (int, float, np.floating, np.integer)) \
                or not np.isfinite(lead) or lead < 0:
            raise ValueError(f"lead: expected a finite number >= 0, got {lead!r}")
        self.volume, self.lead, self.width = volume, float(lead), check_positive(width, "width")
        self.damping = 2.0 * np.sqrt(volume.stiffness)
        self.reset()

    def reset(self) -> None:
        """Forget the shift caused so far (before a new rollout)."""
        self.shift = self.shift_rate = self.target = 0.0
        self.time: float | None = None

    def _advance(self, time: float) -> None:
        """Integrate the copy of the shift (the spring's response to ``target`` held since the last call)."""
        if self.time is not None:
            if time < self.time:
                raise ValueError(f"time: expected non-decreasing times, got {time!r} after {self.time!r}")
            steps = max(1, int(np.ceil((time - self.time) * np.sqrt(self.volume.stiffness) / 0.01)))
            h, stiffness = (time - self.time) / steps, self.volume.stiffness
            for _ in range(steps):        # semi-implicit Euler, about 0.01 of the spring's time constant per step
                self.shift_rate += h * (stiffness * (self.target - self.shift) - self.damping * self.shift_rate)
                self.shift += h * self.shift_rate
        self.time = float(time)

    def acceleration(self, y: np.ndarray, yd: np.ndarray, time: float | None = None) -> np.ndarray:
        """The lifting acceleration ``[d]`` (m/s^2; height dimension only) at position ``y [d]``, velocity ``yd [d]``
        and ``time`` (s since the start; required)."""
        volume = self.volume
        y = as_finite_array(y, "y", ndim=1)
        yd = as_finite_array(yd, "yd", ndim=1)
        if y.shape != yd.shape or max(volume.dims) >= y.size:
            raise ValueError(f"y: expected matching positions and velocities with more than {max(volume.dims)} "
                             f"dimensions, got {y.shape} and {yd.shape}")
        if time is None or not np.isfinite(time):
            raise ValueError(f"time: AdaptiveLift needs the finite time, got {time!r}")
        self._advance(float(time))
        z = volume.dims[2]
        free = (y[z] - self.shift) + self.lead * (yd[z] - self.shift_rate)       # predicted free height
        missing = volume.lift - free
        footprint = float(volume.height(y)) / volume.lift                         # 1 over it, 0 beyond the ramp
        self.target = float(volume.gate(time)) * footprint * 0.5 * (missing + np.sqrt(missing**2 + self.width**2))
        out = np.zeros_like(y)
        out[z] = volume.stiffness * self.target
        return out


def avoiding_rollout(dmp, t: np.ndarray, obstacles: ObstacleAvoidance | list[ObstacleAvoidance], *,
                     smoothing: float = 0.0, stop_at: float | None = None, **start_kwargs
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Roll ``dmp`` out online with the steering terms of ``obstacles`` (the no-learning baseline).

    Args:
        dmp: a :class:`rdmp_gym.RhythmicDMP`.
        t: ``[T]`` evenly spaced times from the start.
        obstacles: one or several terms (:class:`ObstacleAvoidance`, :class:`LiftOver`, :class:`AdaptiveLift`;
            their accelerations add); a term whose ``acceleration`` takes ``time`` gets the time since the start;
            a term with a ``reset`` method is reset first.
        smoothing: time constant (s) of a first-order low-pass on the coupling term (0: none, Hoffmann et
            al.'s term as is). The raw term switches on and off within a few centimetres and, against the stiff
            spring of (4), makes sharp accelerations; 0.1 s cuts the squared jerk by about 10x.
        stop_at: request the stop at this time (a DMP with an ending).
        start_kwargs: passed to :meth:`RhythmicDMP.start` (transient, y0, yd0, anchor, tempo, start_blend).
    Returns:
        positions and velocities, each ``[T, d]``.
    """
    t = check_time_grid(t, "t")
    terms = [obstacles] if hasattr(obstacles, "acceleration") else list(obstacles)
    if not terms or not all(callable(getattr(term, "acceleration", None)) for term in terms):
        raise TypeError("obstacles: expected one or more terms with an acceleration(y, yd) method "
                        "(e.g. ObstacleAvoidance)")
    if not (np.isfinite(smoothing) and smoothing >= 0.0):
        raise ValueError(f"smoothing: expected a time constant >= 0, got {smoothing!r}")
    timed = ["time" in inspect.signature(term.acceleration).parameters for term in terms]
    for term in terms:
        if callable(getattr(term, "reset", None)):
            term.reset()
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
        acceleration = sum(term.acceleration(y, yd, time=stepper.time) if with_time else term.acceleration(y, yd)
                           for term, with_time in zip(terms, timed, strict=True))
        coupling += share * (acceleration / stepper.omega**2 - coupling)
        positions[i], velocities[i] = stepper.step(coupling)
    return positions, velocities
