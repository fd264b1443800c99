"""What a robot executes: acceleration and jerk of a reproduction against a smooth reference.

* :func:`motion_metrics` compares a path sampled on a fine even grid (e.g. 1 kHz) with a reference whose
  derivatives are known, over a mask of samples: position error relative to the reference's range,
  acceleration error relative to the reference's RMS acceleration, integrated squared jerk and peak
  acceleration as ratios to the reference's.
* :class:`SmoothTestSignal` is a smooth composed-periodic test signal with analytic derivatives, built
  independently of :mod:`rdmp_gym.signals.demonstrations`: a periodic pattern of up to three harmonics per
  dimension, entered from rest by a curved transient, so position, velocity, acceleration and jerk are
  exact at any time. Two ways into the pattern: a C4 blend of start and pattern (``join="blend"``), or a
  quintic from rest joined to the orbit at T with matching position, velocity and acceleration
  (``join="quintic"``: C2 at T, the jerk jumps there, as in a start planned to meet a moving pattern);
  either with a curved detour (a bump in the approach) or without.
"""

from __future__ import annotations

from dataclasses import dataclass
from math import comb

import numpy as np
from numpy.polynomial import Polynomial

from ..signals.demonstrations import Demonstration, SyntheticTruth
from ..validation import as_finite_array, check_positive, check_time_grid

__all__ = ["HANDOVER_TARGETS", "JOINS", "SmoothTestSignal", "draw_test_demonstrations", "finite_derivatives",
           "handover_figures", "handover_misses", "integrated_squared_jerk", "motion_metrics", "off_path_peak_ratio",
           "off_path_starts", "peak_acceleration", "random_test_signal", "worst_window_error"]

# C4 blend: 0 -> 1 on [0, 1] with derivatives 1..4 zero at both ends (the minimum-snap profile).
_BLEND = Polynomial([0, 0, 0, 0, 0, 126, -420, 540, -315, 70])
# Detour window u^4 (1 - u)^4 (x 256: peak 1 at u = 1/2), derivatives 0..3 zero at both ends.
_WINDOW = Polynomial([0, 0, 0, 0, 256]) * Polynomial([1, -1]) ** 4
# Quintic Hermite profiles on [0, 1] with value, slope and curvature 0 at u = 0; at u = 1 one of them is 1:
# value, slope, curvature (in that order); the others are 0.
_JOIN = (Polynomial([0, 0, 0, 10, -15, 6]), Polynomial([0, 0, 0, -4, 7, -3]), Polynomial([0, 0, 0, 0.5, -1, 0.5]))
JOINS = ("blend", "quintic")


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


def worst_window_error(Ydd: np.ndarray, acceleration: np.ndarray, dt: float, window: float = 0.2
                       ) -> tuple[float, float]:
    """The largest RMS acceleration error over any ``window`` seconds, relative to the RMS of the reference's
    acceleration over the whole grid, and the time (s from the first sample) at which that window starts.

    ``Ydd``, ``acceleration``: ``[T, d]`` the reproduction's and the reference's acceleration on an even grid.
    A localised fault (a spurious oscillation over a few tenths of a second) hides in an RMS over the whole
    transient; this does not.
    """
    width = max(round(check_positive(window, "window") / dt), 1)
    if Ydd.shape != acceleration.shape or Ydd.shape[0] < width:
        raise ValueError(f"Ydd: expected the reference's shape {acceleration.shape} and at least {width} samples")
    squared = np.concatenate([[0.0], np.cumsum(np.sum((Ydd - acceleration) ** 2, axis=1))])
    windowed = np.sqrt((squared[width:] - squared[:-width]) / width)
    scale = float(np.sqrt(np.mean(np.sum(acceleration**2, axis=1))))
    worst = int(np.argmax(windowed))
    return float(windowed[worst] / scale), worst * dt


def peak_acceleration(Y: np.ndarray, dt: float) -> np.ndarray:
    """Largest acceleration norm (second differences) of paths ``Y [..., T, d]`` on an even grid, ``[...]``."""
    return np.max(np.linalg.norm(np.diff(Y, 2, axis=-2), axis=-1), axis=-1) / dt**2


def off_path_starts(dmp) -> np.ndarray:
    """Canonical initial conditions ``[S, 2]`` (``phi0, r0``) off a fitted DMP's encoded paths: ``phi0`` at 8 phases
    round the circle times ``r0`` at 4 radii from ``mu`` to 3x the largest encoded ``r0``, and midway between
    neighbouring encoded initial conditions (when the DMP has several transients)."""
    encoded = np.array([[start.phi0, start.r0] for start in dmp.transients])
    grid = [(phi0, r0) for phi0 in np.linspace(0.0, 2.0 * np.pi, 8, endpoint=False)
            for r0 in np.linspace(dmp.canonical.mu, 3.0 * encoded[:, 1].max(), 4)]
    if len(encoded) > 1:
        grid += [0.5 * (encoded[k] + encoded[(k + 1) % len(encoded)]) for k in range(len(encoded))]
    return np.array(grid)


def off_path_peak_ratio(dmp, demo_peak: float, duration: float = 6.0, dt: float = 1e-3) -> float:
    """The largest peak acceleration of rollouts of transient 0 from :func:`off_path_starts` (smooth start from the
    demonstrated start) over ``duration`` seconds, relative to ``demo_peak`` (m/s^2, the demonstration's)."""
    t = np.arange(0.0, duration, dt)
    paths = dmp.rollout_batch(off_path_starts(dmp), t, groups=("initial:0",), transient=0)
    return float(peak_acceleration(paths, dt).max() / check_positive(demo_peak, "demo_peak"))


HANDOVER_TARGETS = {"transient acceleration": 0.10, "periodic acceleration": 0.05, "worst window": 0.20,
                    "jerk": 1.5, "transient position": 0.008, "periodic position": 0.003, "off-path peak": 3.0}
"""What a fit of a :class:`SmoothTestSignal` must reach (:func:`handover_figures`): acceleration errors over the
transient and the periodic part and in the worst 0.2 s window, the jerk ratio (the larger of the two parts), the
position errors, and the peak acceleration from canonical starts off the encoded path (x the signal's)."""


def handover_figures(signal: SmoothTestSignal, dmp, duration: float, dt: float = 1e-3) -> dict[str, float]:
    """The figures of :data:`HANDOVER_TARGETS` of ``dmp`` (fitted to a demonstration of ``signal``), rolled out
    over ``duration`` seconds on a grid of ``dt``; also ``worst window from`` (s after T, the window's start)."""
    t = np.arange(0.0, duration + 1e-9, dt)
    position, _, acceleration, jerk = signal.derivatives(t)
    Y = dmp.rollout(t)
    _, Ydd, Yddd = finite_derivatives(Y, dt)
    transient = t < signal.transient_length
    approach = motion_metrics(Y, (position, acceleration, jerk), dt, transient, Ydd, Yddd)
    periodic = motion_metrics(Y, (position, acceleration, jerk), dt, ~transient, Ydd, Yddd)
    window, at = worst_window_error(Ydd, acceleration, dt)
    return {"transient acceleration": approach["acceleration"], "periodic acceleration": periodic["acceleration"],
            "worst window": window, "worst window from": at - signal.transient_length,
            "jerk": max(approach["jerk_ratio"], periodic["jerk_ratio"]), "transient jerk": approach["jerk_ratio"],
            "transient position": approach["position"], "periodic position": periodic["position"],
            "off-path peak": off_path_peak_ratio(dmp, float(peak_acceleration(position, dt)))}


def handover_misses(figures: dict[str, float]) -> list[str]:
    """The names of the :data:`HANDOVER_TARGETS` that ``figures`` (of :func:`handover_figures`) miss."""
    return [name for name, target in HANDOVER_TARGETS.items() if figures[name] > target]


@dataclass(frozen=True)
class SmoothTestSignal:
    """A periodic pattern entered from rest, with exact derivatives.

    ``y(t) = p(t) + (1 - s(u)) (start - p(t)) + w(u) (c1 + (2u - 1) c2)`` for ``u = t / T < 1`` and ``p(t)``
    after, with the periodic pattern ``p(t) = anchor + sum_h a_h cos(h Omega t) + b_h sin(h Omega t)``, the C4
    blend ``s`` and the detour window ``w``. With ``join="quintic"`` the first two terms are replaced by the
    quintic ``q(u)`` from rest at ``start`` that meets the orbit at T with its position, velocity and
    acceleration (``p(T)``, ``p'(T)``, ``p''(T)``: the orbit is entered at the phase ``Omega T``).

    Attributes:
        period: period of the pattern (s).
        transient_length: T (s); the signal is exactly periodic from T on.
        anchor: ``[d]`` mean of the pattern.
        cos_coefficients, sin_coefficients: ``[H, d]`` harmonic amplitudes ``a_h``, ``b_h`` (m).
        start: ``[d]`` where the signal starts, at rest.
        detour: ``[2, d]`` the detour directions ``c1, c2`` (m); zeros for an approach without a bump.
        join: ``"blend"`` (C4 at T) or ``"quintic"`` (C2 at T).
    """

    period: float
    transient_length: float
    anchor: np.ndarray
    cos_coefficients: np.ndarray
    sin_coefficients: np.ndarray
    start: np.ndarray
    detour: np.ndarray
    join: str = "blend"

    def __post_init__(self) -> None:
        if self.join not in JOINS:
            raise ValueError(f"join: expected one of {JOINS}, got {self.join!r}")

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
        c1, c2 = self.detour
        ramp = Polynomial([-1.0, 2.0])
        detour = [(_WINDOW.deriv(n)(u) * c1 + (_WINDOW * ramp).deriv(n)(u) * c2) / length**n
                  for n in range(order + 1)]
        approach = self._quintic(u, order) if self.join == "quintic" else self._blend(u, pattern)
        return [np.where(inside, approach[n] + detour[n], pattern[n]) for n in range(order + 1)]

    def _blend(self, u: np.ndarray, pattern: list[np.ndarray]) -> list[np.ndarray]:
        """``p + (1 - s(u)) (start - p)`` and its time derivatives (Leibniz rule), each ``[T, d]``."""
        order, length = len(pattern) - 1, self.transient_length
        gap = [(self.start if n == 0 else 0.0) - pattern[n] for n in range(order + 1)]   # start - p and derivatives
        keep = [1.0 - _BLEND(u)] + [-_BLEND.deriv(n)(u) / length**n for n in range(1, order + 1)]
        return [pattern[n] + sum(_binomial(n, m) * keep[m] * gap[n - m] for m in range(n + 1))
                for n in range(order + 1)]

    def _quintic(self, u: np.ndarray, order: int) -> list[np.ndarray]:
        """The quintic from rest at ``start`` to the orbit's state at T, and its time derivatives, each ``[T, d]``."""
        length = self.transient_length
        end = [self._pattern(np.array([length]), n)[0] * length**n for n in range(3)]   # in units of u
        end[0] = end[0] - self.start
        return [(self.start if n == 0 else 0.0) + sum(profile.deriv(n)(u) * value
                                                      for profile, value in zip(_JOIN, end, strict=True)) / length**n
                for n in range(order + 1)]

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
    return comb(n, k)


def random_test_signal(rng: np.random.Generator, period: float | None = None, harmonics: int | None = None,
                       transient_length: float | None = None, join: str = "blend", bump: bool = True
                       ) -> SmoothTestSignal:
    """A random :class:`SmoothTestSignal` in 3-D: period in [0.7, 2] s, 1-3 harmonics, transient 1-2.5 s,
    a pattern of 5-12 cm in the table plane (a few mm in height), a start 15-30 cm away, entered by ``join``
    (the orbit's phase at T is random with the coefficients); ``bump=False`` leaves the detour out (the same
    numbers are drawn either way)."""
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
    detour = rng.normal(0.0, 0.04, (2, 3)) * np.array([1.0, 1.0, 0.5]) * float(bump)
    return SmoothTestSignal(period, length, np.zeros(3), cos_coefficients, sin_coefficients, start, detour, join)


def draw_test_demonstrations(rng: np.random.Generator, n: int, join: str = "blend"
                             ) -> list[tuple[SmoothTestSignal, Demonstration]]:
    """``n`` random signals (:func:`random_test_signal`) drawn in sequence from ``rng``, each with its noisy
    demonstration: 100 Hz over the transient plus ``max(6 periods, 5 s)``, white noise of 0.3-0.5 mm. Under
    ``join="quintic"`` every second signal (odd indices) has the bump in the approach, the others none."""
    drawn = []
    for index in range(n):
        signal = random_test_signal(rng, join=join, bump=join == "blend" or index % 2 == 1)
        duration = signal.transient_length + max(6 * signal.period, 5.0)
        drawn.append((signal, signal.demonstration(duration, noise=rng.uniform(3e-4, 5e-4), rng=rng)))
    return drawn
