"""The classic periodic DMP (Ijspeert et al. 2002; Gams et al. 2009), the baseline of the paper.

One phase variable ``phi = phi0 + Omega t`` and periodic basis functions only; the same
transformation system (4) and integrator as :class:`~rdmp_gym.RhythmicDMP`. It is fitted to the
periodic part of a demonstration (a classic rhythmic DMP cannot encode a transient), with the phase
aligned so that the pattern is entered at the demonstrated time; its transient is whatever the
spring produces on the way from the start into the cycle.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..signals.demonstrations import Demonstration
from ..signals.filters import smooth_derivatives
from ..signals.segmentation import Segmentation, segment
from ..validation import as_finite_array, check_count, check_positive, check_time_grid
from .basis import normalize, periodic_width, von_mises
from .fitting import FIT_METHODS, fit_weights, forcing_target
from .transformation import TransformationSystem

__all__ = ["PeriodicDMP"]


class PeriodicDMP:
    """Periodic DMP with one phase variable.

    Args:
        period: period (s).
        weights: ``[d, N]`` weights.
        anchor: ``[d]`` anchor g.
        phi0: phase at the start of the movement.
        start, start_velocity: ``[d]`` default initial state.
        alpha_z: transformation-system gain.
        width: width ``v`` of the von Mises basis functions.
    """

    def __init__(self, period: float, weights: np.ndarray, anchor: np.ndarray, phi0: float, start: np.ndarray,
                 start_velocity: np.ndarray, alpha_z: float = 25.0, width: float | None = None) -> None:
        self.period = check_positive(period, "period")
        self.weights = as_finite_array(weights, "weights", ndim=2)
        d, n = self.weights.shape
        if d < 1 or n < 1:
            raise ValueError(f"weights: expected shape [d, N] with d, N >= 1, got {self.weights.shape}")
        self.anchor = self._vector(anchor, "anchor", d)
        self.phi0 = float(as_finite_array(phi0, "phi0", ndim=0))
        self.start = self._vector(start, "start", d)
        self.start_velocity = self._vector(start_velocity, "start_velocity", d)
        self.alpha_z = check_positive(alpha_z, "alpha_z")
        self.centres = 2.0 * np.pi * np.arange(n) / n
        self.width = periodic_width(n) if width is None else check_positive(width, "width")

    @staticmethod
    def _vector(value: object, name: str, d: int) -> np.ndarray:
        array = as_finite_array(value, name, ndim=1)
        if array.shape != (d,):
            raise ValueError(f"{name}: expected shape ({d},), got {array.shape}")
        return array

    @property
    def omega(self) -> float:
        return 2.0 * np.pi / self.period

    def _normalized(self, phi: np.ndarray) -> np.ndarray:
        return normalize(von_mises(phi, self.centres, np.full(self.centres.size, self.width)))

    @classmethod
    def fit(cls, demos: Demonstration | Sequence[Demonstration], n_periodic: int = 40, method: str = "ridge", *,
            segmentation: Segmentation | None = None, alpha_z: float = 25.0, smoothing: float = 0.15,
            regularization: float = 1e-6) -> PeriodicDMP:
        """Fit the periodic part of one demonstration (the first if several are given)."""
        demo = demos if isinstance(demos, Demonstration) else next(iter(demos))
        if method not in FIT_METHODS:
            raise ValueError(f"method: expected one of {FIT_METHODS}, got {method!r}")
        n_periodic = check_count(n_periodic, "n_periodic", 2)
        seg = segment(demo) if segmentation is None else segmentation
        omega = 2.0 * np.pi / seg.period
        elapsed = demo.t - demo.t[0]
        Y, Yd, Ydd = smooth_derivatives(demo.Y, demo.dt, smoothing)
        periodic = elapsed >= seg.transient_length
        phi0 = -omega * seg.transient_length
        width = periodic_width(int(n_periodic))
        centres = 2.0 * np.pi * np.arange(n_periodic) / n_periodic
        raw = von_mises(phi0 + omega * elapsed[periodic], centres, np.full(int(n_periodic), width))
        target = forcing_target(Y[periodic], Yd[periodic], Ydd[periodic], seg.anchor, omega, alpha_z)
        weights = fit_weights(raw, target, method, regularization)
        return cls(seg.period, weights.T, seg.anchor, phi0, Y[0], Yd[0], alpha_z, width)

    def rollout(self, t: np.ndarray, y0: np.ndarray | None = None, yd0: np.ndarray | None = None,
                anchor: np.ndarray | None = None) -> np.ndarray:
        """Positions ``[T, d]`` at evenly spaced times ``t [T]`` from the start state (default: the demo's)."""
        t = check_time_grid(t, "t")
        elapsed = t - t[0]
        system = TransformationSystem(self.omega, float(elapsed[-1] / (t.size - 1)), self.alpha_z)
        forcing = self._normalized(self.phi0 + self.omega * elapsed) @ self.weights.T
        d = self.anchor.size
        g = self.anchor if anchor is None else self._vector(anchor, "anchor", d)
        y0 = self.start if y0 is None else self._vector(y0, "y0", d)
        yd0 = self.start_velocity if yd0 is None else self._vector(yd0, "yd0", d)
        with np.errstate(all="ignore"):
            y = system.rollout(system.input(g, forcing), y0, yd0 / self.omega)[0]
        if not np.all(np.isfinite(y)):
            raise ValueError(f"rollout: the result overflowed to NaN or inf; the period ({self.period:g} s), gains "
                             "or weights are out of range")
        return y
