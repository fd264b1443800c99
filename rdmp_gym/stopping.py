"""The end of the movement, encoded like the transient start (beyond Ernesti et al. 2012, section VI).

After a stop request the canonical system leaves the limit cycle at an exit phase ``phi_x`` (the
demonstrated one by default) and its radius spirals **inwards** to the origin along a fixed path,
while the phase keeps turning (``tau`` = unit-tempo time since the exit, ``T_s`` the stop length):

    r_s(tau) = r(t) * (1 - s(tau / T_s)),   s(u) = 10u^3 - 15u^4 + 6u^5 (0 before, 1 after)

A third family of basis functions lies on that path, spaced uniformly in time, like the transient
family on the start spiral: ``chi_j = a_s(r_s) exp(-vs_j |pol(phi - rho, r_s) - q_j|^2)`` (``rho``
rotates a non-demonstrated exit phase onto the demonstrated one). Its own fading mirrors (8)-(9) on
the inner side: the periodic family is multiplied by ``g_s(r) = 1`` for ``r >= nu1`` fading to
``delta`` at ``nu2 < nu1``; the stop family has ``a_s(r) = 1`` for ``r <= nu2`` fading to ``delta``
at ``nu1``. All three families share the normalised mixture (5). The anchor blends to the goal,

    g(tau) = g + s((tau - tau_1) / (T_s - tau_1)) (goal - g),   tau_1: where r_s crosses nu1,

so from ``T_s`` on the canonical state rests at the origin (one basis function centred there, fitted
to the demonstrated rest), the anchor is the goal, and the critically damped spring (4) brings the
arm to rest at the goal. Fitting keeps the start and periodic weights of :meth:`RhythmicDMP.fit` and
solves one ridge problem for the stop weights on the demonstration from the exit to its end.
"""

from __future__ import annotations

import inspect
import logging
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .basis import GATE_FLOOR, normalize
from .canonical import CanonicalSystem
from .demonstrations import (
    _DEFAULT_START,
    Demonstration,
    SyntheticTruth,
    _as_generator,
    _check_noise,
    _check_style,
    _composed,
    _smoothstep7,
    _time_grid,
    _vector3,
)
from .fitting import forcing_target, smooth_derivatives
from .rhythm import rest_start
from .segmentation import Segmentation, _change_point, _design, _fit, _harmonics, _normalised, segment
from .transformation import TransformationSystem
from .validation import as_finite_array, check_positive

__all__ = ["Ending", "StopFading", "StopPlan", "StopSegmentation", "ending_demonstration", "exit_time", "fit_ending",
           "fit_stop",
           "minimum_jerk", "plan_stop", "segment_ending"]

logger = logging.getLogger(__name__)

_HEAD_SHARES = (2.0 / 3.0, 0.75, 0.85)
"""Shares of the time to rest tried, in order, as the part of the demonstration that :func:`segment` sees."""


def minimum_jerk(u: np.ndarray) -> np.ndarray:
    """``s(u) = 10u^3 - 15u^4 + 6u^5`` on ``[0, 1]``, 0 before and 1 after (C2), any shape."""
    u = np.clip(u, 0.0, 1.0)
    return u**3 * (10.0 - 15.0 * u + 6.0 * u**2)


def _minimum_jerk_inverse(value: float) -> float:
    """The ``u`` in [0, 1] with ``minimum_jerk(u) = value`` (bisection; ``s`` is monotonic)."""
    low, high = 0.0, 1.0
    for _ in range(60):
        mid = 0.5 * (low + high)
        low, high = (mid, high) if minimum_jerk(np.array(mid)) < value else (low, mid)
    return 0.5 * (low + high)


@dataclass(frozen=True)
class StopFading:
    """The inner-side gates of the stop: ``g_s`` (periodic family) and ``a_s`` (stop family).

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
    def v_tilde(self) -> float:
        return -np.log(self.delta) / (self.nu1 - self.nu2) ** self.k

    def _fade(self, distance: np.ndarray) -> np.ndarray:
        gate = np.exp(-self.v_tilde * distance**self.k)
        return np.where(gate < GATE_FLOOR, 0.0, gate)

    def periodic_gate(self, r: np.ndarray) -> np.ndarray:
        """``g_s(r)``: 1 for r >= nu1, fading below; same shape as ``r``."""
        return self._fade(np.maximum(self.nu1 - r, 0.0))

    def stop_gate(self, r: np.ndarray) -> np.ndarray:
        """``a_s(r)``: 1 for r <= nu2, fading above; same shape as ``r``."""
        return self._fade(np.maximum(r - self.nu2, 0.0))


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


# ---------------------------------------------------------------------------------- demonstrations
def ending_demonstration(style: int = 1, *, rng: np.random.Generator | int | None = 0, n_periods: float = 3.0,
                         stop_length: float = 1.5, rest: float = 1.0,
                         goal: Sequence[float] | np.ndarray = (0.12, -0.10, 0.10), rate: float = 100.0,
                         noise: float = 3e-4, start: Sequence[float] | np.ndarray | None = None,
                         anchor: Sequence[float] | np.ndarray | None = None, period: float | None = None,
                         transient_length: float | None = None) -> Demonstration:
    """A synthetic wiping demonstration ``Y[L, 3]`` that ends: approach, ``n_periods`` periods, then a stop.

    The start and the periodic part are those of :func:`rdmp_gym.wiping_demonstration` (``style``).
    At ``t_e = transient_length + n_periods * period`` the arm lifts off and comes to rest at ``goal``
    (a 7th-order smoothstep of length ``stop_length`` from the running pattern to the goal, so C3), and
    stays there for ``rest`` seconds. ``truth.clean`` holds the noiseless signal.
    """
    kind, complex_approach, default_period, default_transient = _check_style(style)
    period = check_positive(default_period if period is None else period, "period")
    transient = check_positive(default_transient if transient_length is None else transient_length,
                               "transient_length")
    n_periods = check_positive(n_periods, "n_periods")
    stop_length = check_positive(stop_length, "stop_length")
    rest = check_positive(rest, "rest")
    exit_at = transient + n_periods * period
    t = _time_grid(exit_at + stop_length + rest, rate)
    anchor = _vector3(anchor, (0.0, 0.0, 0.0), "anchor")
    running = _composed(t, kind=kind, complex_approach=complex_approach,
                        start=_vector3(start, _DEFAULT_START, "start"), anchor=anchor, period=period,
                        transient_length=transient, entrance_time=0.0)
    blend = _smoothstep7((t - exit_at) / stop_length)[:, None]
    clean = running + blend * (_vector3(goal, (0.0, 0.0, 0.0), "goal") - running)
    noisy = clean + _check_noise(noise) * _as_generator(rng).standard_normal(clean.shape)
    truth = SyntheticTruth(period=period, transient_length=transient, anchor=anchor, clean=clean)
    return Demonstration(t=t, Y=noisy, name=f"wiping style {int(style)} with a stop", truth=truth)


# ---------------------------------------------------------------------------------- segmentation
@dataclass(frozen=True, eq=False)
class StopSegmentation:
    """Where a demonstration that ends leaves its periodic pattern and comes to rest.

    Attributes:
        start: the segmentation of the start and periodic part (:func:`rdmp_gym.segment`).
        periodic_end: time from ``demo.t[0]`` of the last sample that fits the periodic pattern (s).
        rest_time: time from ``demo.t[0]`` from which the demonstration is at rest (s).
        goal: ``[d]`` the rest position (mean over the rest).
    """

    start: Segmentation
    periodic_end: float
    rest_time: float
    goal: np.ndarray


def segment_ending(demo: Demonstration, *, period: float | None = None, rest_fraction: float = 0.05,
                   margin: float = 2.0, n_harmonics: int = 12) -> StopSegmentation:
    """Find the start transient, the periodic part, the stop and the rest in a demonstration that ends.

    Rest: the demonstration is at rest from the first sample after which its speed (smoothed,
    :func:`rdmp_gym.rhythm.motion_speed`) stays below ``rest_fraction`` of its typical speed while it moves (or
    three times its speed in its quietest 0.5 s, where that is higher: sensor noise), for at least 0.2 s; the
    goal is the mean position over the rest. Relative to the motion's own scale, so a slow drift at rest and
    sensor noise pass. Periodic part: :func:`rdmp_gym.segment` on
    the samples up to two thirds of the rest time (so the stop does not enter it; 3/4 or 0.85 of it when
    that shows too little of the periodic part); the Fourier template of the periodic
    part is then extended to the rest, and the end of the periodic part is the change point of its
    noise-scaled residual read backwards (the mirror of how :func:`segment` finds the start). Raises
    ``ValueError`` if the demonstration does not come to rest or shows too little periodic motion.
    """
    if not isinstance(demo, Demonstration):
        raise TypeError(f"demo: expected a Demonstration, got {type(demo).__name__}")
    rest_fraction = check_positive(rest_fraction, "rest_fraction")
    t, dt = demo.t - demo.t[0], demo.dt
    tail = max(round(0.2 / dt), 5)
    if demo.n_samples < 10 * tail:
        raise ValueError(f"demo: too short ({demo.duration:.3g} s) to hold a start, periods and a stop")
    rest_index = rest_start(demo, rest_fraction, min_rest=tail * dt)
    if rest_index is None:
        raise ValueError(f"demo: does not come to rest (its last {tail * dt:.2g} s move faster than "
                         f"{rest_fraction:.0%} of its typical speed)")
    goal = demo.Y[rest_index:].mean(axis=0)
    seg, head = None, 0
    for share in _HEAD_SHARES:       # the shortest head that shows the periodic part (less risk of the stop in it)
        head = round(share * rest_index)
        try:
            seg = segment(Demonstration(demo.t[:head], demo.Y[:head]), period=period, min_periods=1.0,
                          n_harmonics=n_harmonics, margin=margin)
            break
        except ValueError as error:
            reason = error
    if seg is None:
        raise ValueError(f"demo: no periodic part found before the stop ({reason})")
    first = round(seg.transient_length / dt)
    Z, _, _ = _normalised(demo.Y[: rest_index + 1])
    k = _harmonics(head - first, seg.period, dt, n_harmonics)
    coefficients, _ = _fit(t[first:head], Z[first:head], seg.period, k)
    residual = Z - _design(t[: rest_index + 1], seg.period, k) @ coefficients
    dof = max(head - first - coefficients.shape[0], 1)
    noise = np.sqrt(np.sum(residual[first:head] ** 2, axis=0) / dof)
    scaled = residual / np.maximum(noise, 1e-6)
    # read the part after the start transient backwards: the stop becomes a "transient"
    backwards = _change_point(scaled[first:][::-1], margin)
    periodic_end = t[rest_index - backwards]
    if periodic_end <= t[head - 1] - 0.5 * seg.period:
        raise ValueError("demo: the periodic part ends too early to segment the stop")
    logger.debug("segment_ending %r: periodic until %.3f s, at rest from %.3f s", demo.name, periodic_end,
                 t[rest_index])
    return StopSegmentation(seg, float(periodic_end), float(t[rest_index]), goal)


# ---------------------------------------------------------------------------------- fitting
def _stop_basis(canonical: CanonicalSystem, exit_phase: float, r_exit: float, length: float, first: float,
                n_stop: int, overlap: float) -> tuple[np.ndarray, np.ndarray]:
    """Centres ``[S, 2]`` on the stop path at times uniform in ``[first, length]`` (the last at the origin),
    widths ``[S]`` that make neighbours cross at ``overlap``."""
    times = np.linspace(first, length, n_stop)
    radius = r_exit * (1.0 - minimum_jerk(times / length))
    angle = exit_phase + canonical.omega * times
    centres = np.stack([radius * np.cos(angle), radius * np.sin(angle)], axis=1)
    gaps = np.linalg.norm(np.diff(centres, axis=0), axis=1)
    spacing = np.empty(n_stop)
    spacing[0], spacing[-1] = gaps[0], gaps[-1]
    spacing[1:-1] = 0.5 * (gaps[1:] + gaps[:-1])
    return centres, np.log(1.0 / overlap) / (0.5 * np.maximum(spacing, 1e-12)) ** 2


def fit_ending(demo: Demonstration, n_stop: int = 15, *,
               segmentation: StopSegmentation | None = None, nu1_factor: float = 0.9, nu2_factor: float = 0.7,
               stop_overlap: float = 0.9, rest_margin: float = 0.15, **fit_kwargs):
    """Fit a DMP with a start transient, the periodic pattern and a stop from one demonstration that ends.

    The start and periodic weights come from :meth:`RhythmicDMP.fit` on the demonstration up to the end
    of its periodic part; the ``n_stop`` stop weights from one ridge regression (on the normalised mixture
    of all three families, start and periodic weights held) on the samples from the exit to the end.
    The canonical exit is placed so that the fade from the periodic to the stop family (``r_s`` from ``nu1``
    to ``nu2``) is centred on the detected end of the periodic part.

    Args:
        demo: a demonstration that ends (see :func:`segment_ending`).
        n_stop: stop basis functions S (>= 2).
        segmentation: from :func:`segment_ending`; estimated when omitted.
        nu1_factor, nu2_factor: the inner fading radii ``nu = factor * mu`` (``nu2 < nu1 < 1``; the stop
            family's gate on the cycle, ``delta ** (((1 - nu2) / (nu1 - nu2)) ** 4)``, must be negligible).
        stop_overlap: height at which neighbouring stop basis functions cross.
        rest_margin: the canonical stop path reaches the origin this share of the stop duration after the
            detected rest (the detection leads the true rest of a smooth approach).
        fit_kwargs: passed on to :meth:`RhythmicDMP.fit` (``n_periodic``, ``n_transient``, ``smoothing``, ...);
            the stop uses the same ``delta``, ``smoothing`` and ``regularization`` (those of
            :meth:`RhythmicDMP.fit` unless given).
    Returns:
        a :class:`RhythmicDMP` with ``ending`` set.
    """
    from .dmp import RhythmicDMP

    _check_stop_settings(n_stop, nu1_factor, nu2_factor)
    seg = segment_ending(demo) if segmentation is None else segmentation
    end_index = round(seg.periodic_end / demo.dt)
    head = Demonstration(demo.t[: end_index + 1], demo.Y[: end_index + 1], name=demo.name)
    if "segmentations" in fit_kwargs:
        raise ValueError("segmentations: give the StopSegmentation as segmentation=")
    defaults = inspect.signature(RhythmicDMP.fit).parameters
    delta, smoothing, regularization = (fit_kwargs.get(name, defaults[name].default)
                                        for name in ("delta", "smoothing", "regularization"))
    dmp = RhythmicDMP.fit(head, segmentations=[seg.start], **fit_kwargs)
    method = fit_kwargs.get("method", defaults["method"].default)
    return fit_stop(dmp, demo, seg, n_stop, nu1_factor=nu1_factor, nu2_factor=nu2_factor, stop_overlap=stop_overlap,
                    rest_margin=rest_margin, delta=delta, regularization=regularization, method=method,
                    substeps=int(fit_kwargs.get("substeps", defaults["substeps"].default)), smoothing=smoothing)


def _check_stop_settings(n_stop: int, nu1_factor: float, nu2_factor: float) -> None:
    if int(n_stop) < 2:
        raise ValueError(f"n_stop: expected at least 2, got {n_stop}")
    if not 0.0 < nu2_factor < nu1_factor < 1.0:
        raise ValueError(f"nu1_factor, nu2_factor: expected 0 < nu2_factor < nu1_factor < 1, "
                         f"got {nu1_factor!r}, {nu2_factor!r}")


def fit_stop(dmp, demo: Demonstration, seg: StopSegmentation, n_stop: int = 15, *, nu1_factor: float = 0.9,
             nu2_factor: float = 0.7, stop_overlap: float = 0.9, rest_margin: float = 0.15, delta: float = 1e-3,
             regularization: float | None = None, method: str = "trajectory", substeps: int = 4,
             smoothing: float = 0.15):
    """``dmp`` (a fitted :class:`RhythmicDMP` that reproduces ``demo`` up to its stop) with a stop fitted to the rest
    of ``demo``: the stop family's ``n_stop`` weights by one ridge regression, start and periodic weights held.
    ``method="trajectory"`` matches the rollout's positions (and follows an anchor that travels with
    ``dmp.sweep``); ``"lwr"``/``"ridge"`` match the forcing target (10) (a fixed anchor). Other arguments as in
    :func:`fit_ending`. Returns a copy of ``dmp`` with ``ending`` set."""
    _check_stop_settings(n_stop, nu1_factor, nu2_factor)
    if regularization is None:          # resolved per method, as in RhythmicDMP.fit
        regularization = 1e-4 if method == "trajectory" else 1e-6
    dt = demo.dt
    canonical, mu = dmp.canonical, dmp.canonical.mu
    fading = StopFading(nu1_factor * mu, nu2_factor * mu, delta=delta)
    u1 = _minimum_jerk_inverse(1.0 - nu1_factor)
    u2 = _minimum_jerk_inverse(1.0 - nu2_factor)
    # the fade window of the two families is centred on the detected end of the periodic part (which lags the
    # true one: a smooth departure stays within the noise for a while), and the canonical path reaches the
    # origin ``rest_margin`` of the stop duration after the detected rest (which leads the true one)
    u_mid = 0.5 * (u1 + u2)
    length = (1.0 + rest_margin) * (seg.rest_time - seg.periodic_end) / (1.0 - u_mid)
    exit_at = seg.periodic_end - u_mid * length
    if exit_at <= dmp.transients[0].length:
        raise ValueError("demo: the stop begins before the start transient has ended")
    start = dmp.transients[0]
    exit_phase = float(np.mod(start.phi0 + canonical.omega * exit_at, 2.0 * np.pi))
    r_exit = float(canonical.radius(np.array([exit_at]), start.r0)[0])
    centres, widths = _stop_basis(canonical, exit_phase, r_exit, length, 0.5 * (u1 + u2) * length,
                                  int(n_stop), stop_overlap)
    ending = Ending(exit_phase, length, u1 * length, seg.goal, centres, widths,
                    np.zeros((dmp.n_dims, int(n_stop))), fading)

    if method == "trajectory":
        stop_weights = _trajectory_stop_weights(dmp.with_ending(ending), demo, exit_at, substeps, regularization)
    else:
        rows = slice(int(np.floor(exit_at / dt)), None)
        t = demo.t[rows] - demo.t[0]
        Y, Yd, Ydd = (array[rows] for array in smooth_derivatives(demo.Y, dt, smoothing))
        phi, r = canonical.state(t, start.phi0, start.r0)
        tau = t - exit_at
        anchor = dmp.anchor + ending.anchor_blend(tau)[:, None] * (seg.goal - dmp.anchor)
        target = forcing_target(Y, Yd, Ydd, anchor, canonical.omega, dmp.alpha_z)
        normalized = normalize(ending.mixture(dmp.basis, phi, r, tau, 0.0), dmp.basis.fading.floor)
        held, free = normalized[:, : dmp.basis.n_basis], normalized[:, dmp.basis.n_basis:]
        stop_weights = _ridge(free, target - held @ dmp.weights.T, regularization)
    logger.info("fitted a stop: exit phase %.3f rad, stop length %.3f s, S=%d", exit_phase, length, n_stop)
    return dmp.with_ending(ending.with_weights(stop_weights))


def _ridge(design: np.ndarray, target: np.ndarray, regularization: float) -> np.ndarray:
    """Weights ``[d, S]`` of ``design [L, S] @ W.T ~ target [L, d]`` with a ridge relative to the mean diagonal."""
    gram = design.T @ design
    lam = regularization * max(float(np.mean(np.diag(gram))), 1e-300)
    return np.linalg.solve(gram + lam * np.eye(gram.shape[0]), design.T @ target).T


def _trajectory_stop_weights(dmp, demo: Demonstration, exit_at: float, substeps: int,
                             regularization: float) -> np.ndarray:
    """Stop weights ``[d, S]`` that make the DMP's own rollout (smooth start, stop at ``exit_at``) match the
    sampled positions from the exit on, as :meth:`RhythmicDMP.fit`'s ``method="trajectory"`` does for the
    other weights: the rollout is its path with zero stop weights plus the spring's response to each stop
    basis function (simulated ``substeps`` times finer than the samples); one ridge problem, no derivatives
    of the noisy samples."""
    ending, canonical = dmp.ending, dmp.canonical
    start = dmp.transients[0]
    fine = np.arange((demo.n_samples - 1) * substeps + 1) * (demo.dt / substeps)
    zero = dmp.with_ending(ending.with_weights(np.zeros_like(ending.weights)))
    free = zero.rollout(fine, stop_at=exit_at - 1e-9, tempo=1.0)[::substeps]            # [L, d]
    phi, r = canonical.state(fine, start.phi0, start.r0)
    columns = normalize(ending.mixture(dmp.basis, phi, r, fine - exit_at, 0.0),
                        dmp.basis.fading.floor)[:, dmp.basis.n_basis:]                   # [T_fine, S]
    system = TransformationSystem(canonical.omega, demo.dt / substeps, dmp.alpha_z)
    zeros = np.zeros(ending.n_basis)
    response = system.rollout(system.input(zeros, columns), zeros, zeros)[0][::substeps]  # [L, S]
    rows = slice(int(np.floor(exit_at / demo.dt)), None)
    return _ridge(response[rows], demo.Y[rows] - free[rows], regularization)


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
