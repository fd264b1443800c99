"""The stop's formulation: the canonical system's exit from the cycle, its inner gates and the stop family of
basis functions (:class:`Ending`), and when a requested stop happens (:func:`plan_stop`). The DMP uses these;
:mod:`rdmp_gym.dmp.stopping` fits them to a demonstration (see there for the equations).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..validation import as_finite_array, check_positive
from .basis import FadeBand

__all__ = ["Ending", "StopFading", "StopPlan", "StopRequest", "exit_time", "minimum_jerk", "minimum_jerk_inverse",
           "plan_stop"]


@dataclass(frozen=True)
class StopRequest:
    """The end of a rollout: a stop requested ``at`` seconds after the start leaves the cycle at the next
    demonstrated exit phase (or at ``exit_phase``, rad) and comes to rest at ``goal`` (``[d]``, or ``[B, d]`` in a
    batch; default: the demonstrated goal, moved and transformed with the anchor). A plain number for ``stop_at``
    is ``StopRequest(at=number)``."""

    at: float
    exit_phase: float | None = None
    goal: np.ndarray | None = None

    @classmethod
    def of(cls, stop_at: float | StopRequest | None) -> StopRequest | None:
        """``stop_at`` as a request (``None``: no stop)."""
        return stop_at if stop_at is None or isinstance(stop_at, StopRequest) else cls(stop_at)


def minimum_jerk(u: np.ndarray) -> np.ndarray:
    """``s(u) = 10u^3 - 15u^4 + 6u^5`` on ``[0, 1]``, 0 before and 1 after (C2), any shape."""
    u = np.clip(u, 0.0, 1.0)
    return u**3 * (10.0 - 15.0 * u + 6.0 * u**2)


def minimum_jerk_inverse(value: float) -> float:
    """The ``u`` in [0, 1] with ``minimum_jerk(u) = value`` (bisection; ``s`` is monotonic)."""
    low, high = 0.0, 1.0
    for _ in range(60):
        mid = 0.5 * (low + high)
        low, high = (mid, high) if minimum_jerk(np.array(mid)) < value else (low, mid)
    return 0.5 * (low + high)


@dataclass(frozen=True)
class StopFading(FadeBand):
    """The inner-side gates of the stop: ``g_s`` (periodic family) and ``a_s`` (stop family), the start's
    :class:`~rdmp_gym.dmp.basis.FadeBand` mirrored: across ``[nu2, nu1]``, the stop family inside, the periodic outside.

    Args:
        nu1: radius below which the periodic family fades (``g_s(nu1) = 1``, ``a_s(nu1) = delta``).
        nu2: radius below which only the stop family is active (``< nu1``).
        k: exponent of the fade.
        delta: ``g_s(nu2) = a_s(nu1) = delta``.
    """

    nu1: float
    nu2: float
    k: int = 4
    delta: float = 1e-3

    def __post_init__(self) -> None:
        check_positive(self.nu2, "nu2")
        if not self.nu1 > self.nu2:
            raise ValueError(f"nu1: must exceed nu2 = {self.nu2:g}, got {self.nu1!r}")
        if not 0.0 < self.delta < 1.0:
            raise ValueError(f"delta: must lie in (0, 1), got {self.delta!r}")

    @property
    def inner(self) -> float:
        return self.nu2

    @property
    def outer(self) -> float:
        return self.nu1

    def periodic_gate(self, r: np.ndarray) -> np.ndarray:
        """``g_s(r)``: 1 for r >= nu1, fading below; same shape as ``r``."""
        return self.outer_gate(r)

    def stop_gate(self, r: np.ndarray) -> np.ndarray:
        """``a_s(r)``: 1 for r <= nu2, fading above; same shape as ``r``."""
        return self.inner_gate(r)


@dataclass(frozen=True, eq=False)
class Ending:
    """The encoded end of the movement (the stop transient).

    Attributes:
        exit_phase: canonical phase at which the demonstrated stop leaves the cycle (rad, [0, 2 pi)).
        length: ``T_s``, unit-tempo time from the exit until the canonical state rests at the origin (s).
        blend_start: ``tau_1``, time after the exit at which the anchor starts to move to the goal (s).
        goal: ``[d]`` the demonstrated rest position.
        centres: ``[S, 2]`` phase-plane centres of the stop basis functions.
        widths: ``[S]`` their widths.
        weights: ``[d, S]`` their weights.
        fading: the inner-side gates.
    """

    exit_phase: float
    length: float
    blend_start: float
    goal: np.ndarray
    centres: np.ndarray
    widths: np.ndarray
    weights: np.ndarray
    fading: StopFading

    def __post_init__(self) -> None:
        check_positive(self.length, "length")
        if not 0.0 <= float(self.blend_start) < float(self.length):
            raise ValueError(f"blend_start: expected a value in [0, length={self.length}), got {self.blend_start!r}")
        for name, ndim in (("goal", 1), ("centres", 2), ("widths", 1), ("weights", 2)):
            object.__setattr__(self, name, as_finite_array(getattr(self, name), name, ndim=ndim))
        n_stop = self.widths.size
        if self.centres.shape != (n_stop, 2) or self.weights.shape != (self.goal.size, n_stop):
            raise ValueError(f"weights: expected centres [{n_stop}, 2] and weights [{self.goal.size}, {n_stop}], "
                             f"got {self.centres.shape} and {self.weights.shape}")
        object.__setattr__(self, "exit_phase", float(np.mod(self.exit_phase, 2.0 * np.pi)))

    @property
    def n_basis(self) -> int:
        return int(self.widths.size)

    def radius_factor(self, tau: np.ndarray) -> np.ndarray:
        """``1 - s(tau / T_s)``: 1 before the exit, 0 from ``T_s`` on; ``tau [T]`` unit-tempo time since the exit."""
        return 1.0 - minimum_jerk(tau / self.length)

    def anchor_blend(self, tau: np.ndarray) -> np.ndarray:
        """Share ``[T]`` of the way from the anchor to the goal at unit-tempo time ``tau`` since the exit."""
        return minimum_jerk((tau - self.blend_start) / (self.length - self.blend_start))

    def activations(self, phi: np.ndarray, r: np.ndarray) -> np.ndarray:
        """Raw stop activations ``[T, S]`` at (already rotated) phases ``phi [T]`` and stop radii ``r [T]``."""
        q = self.centres
        distance_sq = (r[:, None] ** 2 + np.sum(q**2, axis=1)
                       - 2.0 * r[:, None] * (np.cos(phi)[:, None] * q[:, 0] + np.sin(phi)[:, None] * q[:, 1]))
        return np.exp(-self.widths * np.maximum(distance_sq, 0.0)) * self.fading.stop_gate(r)[:, None]

    def mixture(self, basis, phi: np.ndarray, r: np.ndarray, tau: np.ndarray, rotation: float) -> np.ndarray:
        """Raw activations ``[T, D + S]`` of all three families along a path that exits at ``tau = 0``.

        ``phi, r [T]`` are the unstopped canonical state, ``tau [T]`` unit-tempo time since the exit
        (negative before it), ``rotation`` the phase offset of this exit from the demonstrated one.
        Before the exit the result is the unstopped activations with zero stop columns (exactly).
        """
        stopping = tau >= 0.0
        r_stop = np.where(stopping, r * self.radius_factor(tau), r)
        raw = basis.activations(phi, r_stop)
        raw[:, : basis.n_periodic] *= self.fading.periodic_gate(r_stop)[:, None]
        stop = np.zeros((phi.size, self.n_basis))
        if np.any(stopping):
            stop[stopping] = self.activations(phi[stopping] - rotation, r_stop[stopping])
        return np.concatenate([raw, stop], axis=1)

    def forcing(self, basis, phi: np.ndarray, r: np.ndarray, tau: np.ndarray, rotation: float,
                weights: np.ndarray, stop_weights: np.ndarray) -> np.ndarray:
        """The forcing term (5) with the stop family: ``weights [..., d, D]``, ``stop_weights [..., d, S]``
        -> ``[..., T, d]``."""
        raw = self.mixture(basis, phi, r, tau, rotation)
        full = np.concatenate([weights, stop_weights], axis=-1)
        return (raw @ np.swapaxes(full, -1, -2)) / (raw.sum(axis=-1, keepdims=True) + basis.fading.floor)

    def to_dict(self) -> dict:
        """JSON-ready numbers (the optional ``stop`` field of a DMP file)."""
        return {"exit_phase": self.exit_phase, "length": self.length, "blend_start": self.blend_start,
                "goal": self.goal.tolist(), "centres": self.centres.tolist(), "widths": self.widths.tolist(),
                "weights": self.weights.tolist(),
                "fading": {"nu1": self.fading.nu1, "nu2": self.fading.nu2, "k": self.fading.k,
                           "delta": self.fading.delta}}

    def with_weights(self, weights: np.ndarray) -> Ending:
        """The same ending with new stop weights ``[d, S]``."""
        return Ending(self.exit_phase, self.length, self.blend_start, self.goal, self.centres, self.widths,
                      weights, self.fading)


def exit_time(request: float, phase0: float, omega: float, exit_phase: float) -> float:
    """First time ``>= request`` at which the phase ``phase0 + omega t`` equals ``exit_phase`` mod 2 pi (s)."""
    turns = np.ceil((phase0 + omega * request - exit_phase) / (2.0 * np.pi) - 1e-12)
    return float((exit_phase + 2.0 * np.pi * turns - phase0) / omega)


@dataclass(frozen=True, eq=False)
class StopPlan:
    """One requested stop of a rollout.

    Attributes:
        exit_time: time after the start of the rollout at which the canonical system leaves the cycle (s).
        rotation: phase of this exit minus the demonstrated exit phase (rad; 0 at the demonstrated phase).
        goal: ``[B, d]`` where each movement comes to rest.
    """

    exit_time: float
    rotation: float
    goal: np.ndarray


def plan_stop(ending: Ending, stop_at: float, phi0: float, omega: float, goal: np.ndarray,
              exit_phase: float | None = None) -> StopPlan:
    """The stop that a request at time ``stop_at`` (s after the start) leads to: the exit at the next
    demonstrated exit phase (or at ``exit_phase``), on a phase ``phi0 + omega t`` (``omega`` with tempo)."""
    stop_at = float(as_finite_array(stop_at, "stop_at", ndim=0))
    if stop_at < 0.0:
        raise ValueError(f"stop_at: expected a time >= 0, got {stop_at!r}")
    target = ending.exit_phase if exit_phase is None else float(as_finite_array(exit_phase, "exit_phase", ndim=0))
    when = exit_time(stop_at, phi0, omega, target)
    return StopPlan(when, float(target - ending.exit_phase), goal)
