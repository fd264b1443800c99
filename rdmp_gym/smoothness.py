"""What a robot executes: acceleration and jerk of a reproduction against a smooth reference.

* :func:`motion_metrics` compares a path sampled on a fine even grid (e.g. 1 kHz) with a reference whose
  derivatives are known, over a mask of samples: position error relative to the reference's range,
  acceleration error relative to the reference's RMS acceleration, integrated squared jerk and peak
  acceleration as ratios to the reference's.
* :class:`SmoothTestSignal` is a smooth composed-periodic test signal with analytic derivatives, built
  independently of :mod:`rdmp_gym.demonstrations`: a periodic pattern of up to three harmonics per
  dimension, entered from rest by a curved transient (a C4 blend plus a curved detour), so position,
  velocity, acceleration and jerk are exact at any time.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.polynomial import Polynomial

from .demonstrations import Demonstration, SyntheticTruth
from .validation import as_finite_array, check_positive, check_time_grid

__all__ = ["SmoothTestSignal", "finite_derivatives", "integrated_squared_jerk", "motion_metrics", "random_test_signal"]

# C4 blend: 0 -> 1 on [0, 1] with derivatives 1..4 zero at both ends (the minimum-snap profile).
_BLEND = Polynomial([0, 0, 0, 0, 0, 126, -420, 540, -315, 70])
# Detour window u^4 (1 - u)^4 (x 256: peak 1 at u = 1/2), derivatives 0..3 zero at both ends.
_WINDOW = Polynomial([0, 0, 0, 0, 256]) * Polynomial([1, -1]) ** 4


def finite_derivatives(Y: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Velocity, acceleration and jerk of ``Y [T, d]`` on an even grid (second-order central differences, and
    second-order one-sided ones at both ends: first-order ends, applied three times, make the jerk of the last
    samples wrong by about ``acceleration / dt``, as much as the whole integrated jerk of a smooth signal)."""
    velocity = np.gradient(Y, dt, axis=0, edge_order=2)
    acceleration = np.gradient(velocity, dt, axis=0, edge_order=2)
    return velocity, acceleration, np.gradient(acceleration, dt, axis=0, edge_order=2)


def integrated_squared_jerk(path: np.ndarray, dt: float) -> float:
    """``∫ |d³y/dt³|² dt`` of a path ``[T, d]`` sampled every ``dt`` (third differences; the smoothness
    measure of commanded paths in the agents' protocol and the env baselines)."""
    jerk = np.diff(path, n=3, axis=0) / dt**3
    return float(np.sum(jerk**2) * dt)


def motion_metrics(Y: np.ndarray, reference: tuple[np.ndarray, np.ndarray, np.ndarray], dt: float,
                   mask: np.ndarray, Ydd: np.ndarray | None = None, Yddd: np.ndarray | None = None
                   ) -> dict[str, float]:
    """Position, acceleration and jerk fidelity of ``Y [T, d]`` (even grid ``dt``) over ``mask [T]``.

    Args:
        Y: the reproduction.
        reference: ``(position, acceleration, jerk)`` of the reference, each ``[T, d]``.
        dt: grid step (s).
        mask: which samples to compare.
        Ydd, Yddd: the reproduction's acceleration and jerk; finite differences of ``Y`` when omitted.
    Returns:
        ``position`` (RMS error / largest range of the reference), ``acceleration`` (RMS error / RMS of the
        reference's acceleration), ``jerk_ratio`` (integrated squared jerk / the reference's) and
        ``peak_acceleration_ratio`` (largest acceleration norm / the reference's), all over ``mask``.
    """
    position, acceleration, jerk = reference
    if Ydd is None or Yddd is None:
        _, Ydd, Yddd = finite_derivatives(Y, dt)

    def rms(values: np.ndarray) -> float:
        return float(np.sqrt(np.mean(np.sum(values[mask] ** 2, axis=1))))

    return {
        "position": rms(Y - position) / float(np.ptp(position, axis=0).max()),
        "acceleration": rms(Ydd - acceleration) / rms(acceleration),
        "jerk_ratio": float(np.sum(Yddd[mask] ** 2) / np.sum(jerk[mask] ** 2)),
        "peak_acceleration_ratio": float(np.linalg.norm(Ydd[mask], axis=1).max()
                                         / np.linalg.norm(acceleration[mask], axis=1).max()),
    }


@dataclass(frozen=True)
class SmoothTestSignal:
    """A periodic pattern entered from rest, with exact derivatives.

    ``y(t) = p(t) + (1 - s(u)) (start - p(t)) + w(u) (c1 + (2u - 1) c2)`` for ``u = t / T < 1`` and ``p(t)``
    after, with the periodic pattern ``p(t) = anchor + sum_h a_h cos(h Omega t) + b_h sin(h Omega t)``, the C4
    blend ``s`` and the detour window ``w``.

    Attributes:
        period: period of the pattern (s).
        transient_length: T (s); the signal is exactly periodic from T on.
        anchor: ``[d]`` mean of the pattern.
        cos_coefficients, sin_coefficients: ``[H, d]`` harmonic amplitudes ``a_h``, ``b_h`` (m).
        start: ``[d]`` where the signal starts, at rest.
        detour: ``[2, d]`` the detour directions ``c1, c2`` (m).
    """

    period: float
    transient_length: float
    anchor: np.ndarray
    cos_coefficients: np.ndarray
    sin_coefficients: np.ndarray
    start: np.ndarray
    detour: np.ndarray

    def _pattern(self, t: np.ndarray, order: int) -> np.ndarray:
        """``order``-th time derivative of ``p`` at ``t [T]``, ``[T, d]``."""
        omega = 2.0 * np.pi / self.period
        harmonics = np.arange(1, self.cos_coefficients.shape[0] + 1)
        angle = omega * harmonics * t[:, None]                                         # [T, H]
        # d^n/dt^n cos(x) = cos(x + n pi/2) (h Omega)^n, likewise for sin.
        gain = (omega * harmonics) ** order
        shift = order * np.pi / 2.0
        out = ((np.cos(angle + shift) * gain) @ self.cos_coefficients
               + (np.sin(angle + shift) * gain) @ self.sin_coefficients)
        return out + (self.anchor if order == 0 else 0.0)

    def derivatives(self, t: np.ndarray, order: int = 3) -> list[np.ndarray]:
        """Position and its first ``order`` time derivatives at ``t [T]`` (s from the start), each ``[T, d]``."""
        t = as_finite_array(t, "t", ndim=1)
        length = self.transient_length
        u = np.clip(t / length, 0.0, 1.0)[:, None]
        inside = (t < length)[:, None]
        pattern = [self._pattern(t, n) for n in range(order + 1)]
        gap = [(self.start if n == 0 else 0.0) - pattern[n] for n in range(order + 1)]   # start - p and derivatives
        keep = [1.0 - _BLEND(u)] + [-_BLEND.deriv(n)(u) / length**n for n in range(1, order + 1)]
        c1, c2 = self.detour
        ramp = Polynomial([-1.0, 2.0])
        detour = [(_WINDOW.deriv(n)(u) * c1 + (_WINDOW * ramp).deriv(n)(u) * c2) / length**n
                  for n in range(order + 1)]
        out = []
        for n in range(order + 1):
            # Leibniz rule for (1 - s) (start - p)
            blended = sum(_binomial(n, m) * keep[m] * gap[n - m] for m in range(n + 1))
            out.append(pattern[n] + np.where(inside, blended + detour[n], 0.0))
        return out

    def demonstration(self, duration: float, rate: float = 100.0, noise: float = 4e-4,
                      rng: np.random.Generator | int | None = 0) -> Demonstration:
        """Samples at ``rate`` Hz over ``[0, duration]`` with white noise of std ``noise`` (m)."""
        n_samples = int(np.floor(check_positive(duration, "duration") * rate + 1e-9)) + 1
        t = check_time_grid(np.arange(n_samples) / rate, "t")
        clean = self.derivatives(t, order=0)[0]
        generator = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
        noisy = clean + noise * generator.standard_normal(clean.shape)
        truth = SyntheticTruth(period=self.period, transient_length=self.transient_length,
                               anchor=self.anchor, clean=clean)
        return Demonstration(t, noisy, name="smooth test signal", truth=truth)


def _binomial(n: int, k: int) -> int:
    from math import comb

    return comb(n, k)


def random_test_signal(rng: np.random.Generator, period: float | None = None, harmonics: int | None = None,
                       transient_length: float | None = None) -> SmoothTestSignal:
    """A random :class:`SmoothTestSignal` in 3-D: period in [0.7, 2] s, 1-3 harmonics, transient 1-2.5 s,
    a pattern of 5-12 cm in the table plane (a few mm in height), a start 15-30 cm away."""
    period = float(rng.uniform(0.7, 2.0)) if period is None else period
    harmonics = int(rng.integers(1, 4)) if harmonics is None else harmonics
    length = float(rng.uniform(1.0, 2.5)) if transient_length is None else transient_length
    scale = np.array([1.0, 1.0, 0.05]) * rng.uniform(0.025, 0.06)
    decay = 1.0 / np.arange(1, harmonics + 1) ** 1.5
    cos_coefficients = rng.normal(0.0, 1.0, (harmonics, 3)) * decay[:, None] * scale
    sin_coefficients = rng.normal(0.0, 1.0, (harmonics, 3)) * decay[:, None] * scale
    angle = rng.uniform(0.0, 2.0 * np.pi)
    distance = rng.uniform(0.15, 0.3)
    start = np.array([distance * np.cos(angle), distance * np.sin(angle), rng.uniform(0.05, 0.12)])
    detour = rng.normal(0.0, 0.04, (2, 3)) * np.array([1.0, 1.0, 0.5])
    return SmoothTestSignal(period, length, np.zeros(3), cos_coefficients, sin_coefficients, start, detour)
