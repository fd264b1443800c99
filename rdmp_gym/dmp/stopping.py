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

This module fits the stop (:func:`fit_ending`, :func:`fit_stop`). The formulation's objects (:class:`Ending`, the
gates, when a requested stop happens) are in :mod:`rdmp_gym.dmp.ending`; the demonstration's segmentation is
:func:`rdmp_gym.signals.segmentation.segment_ending`; a synthetic demonstration that ends is
:func:`rdmp_gym.synthetic.demonstrations.ending_demonstration`.
"""

from __future__ import annotations

import logging

import numpy as np

from ..signals.demonstrations import Demonstration
from ..signals.filters import smooth_derivatives
from ..signals.segmentation import StopSegmentation, segment_ending
from .basis import normalize
from .canonical import CanonicalSystem
from .ending import Ending, StopFading, minimum_jerk, minimum_jerk_inverse
from .fitting import forcing_target
from .rhythmic import RhythmicDMP
from .settings import FitSettings
from .transformation import TransformationSystem

__all__ = ["fit_ending", "fit_stop"]

logger = logging.getLogger(__name__)


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
    _check_stop_settings(n_stop, nu1_factor, nu2_factor)
    seg = segment_ending(demo) if segmentation is None else segmentation
    end_index = round(seg.periodic_end / demo.dt)
    head = Demonstration(demo.t[: end_index + 1], demo.Y[: end_index + 1], name=demo.name)
    if "segmentations" in fit_kwargs:
        raise ValueError("segmentations: give the StopSegmentation as segmentation=")
    fit = FitSettings.resolve(fit_kwargs.get("settings"), **{name: value for name, value in fit_kwargs.items()
                                                             if name in FitSettings.names()})
    dmp = RhythmicDMP.fit(head, segmentations=[seg.start], **fit_kwargs)
    return fit_stop(dmp, demo, seg, n_stop, nu1_factor=nu1_factor, nu2_factor=nu2_factor, stop_overlap=stop_overlap,
                    rest_margin=rest_margin, settings=fit)


def _check_stop_settings(n_stop: int, nu1_factor: float, nu2_factor: float) -> None:
    if int(n_stop) < 2:
        raise ValueError(f"n_stop: expected at least 2, got {n_stop}")
    if not 0.0 < nu2_factor < nu1_factor < 1.0:
        raise ValueError(f"nu1_factor, nu2_factor: expected 0 < nu2_factor < nu1_factor < 1, "
                         f"got {nu1_factor!r}, {nu2_factor!r}")


def fit_stop(dmp, demo: Demonstration, seg: StopSegmentation, n_stop: int = 15, *, nu1_factor: float = 0.9,
             nu2_factor: float = 0.7, stop_overlap: float = 0.9, rest_margin: float = 0.15,
             settings: FitSettings | None = None):
    """``dmp`` (a fitted :class:`RhythmicDMP` that reproduces ``demo`` up to its stop) with a stop fitted to the rest
    of ``demo``: the stop family's ``n_stop`` weights by one ridge regression, start and periodic weights held.
    ``method="trajectory"`` matches the rollout's positions (and follows an anchor that travels with
    ``dmp.sweep``); ``"lwr"``/``"ridge"`` match the forcing target (10) (a fixed anchor). Other arguments as in
    :func:`fit_ending`; the stop shares the fit's ``settings`` (:class:`~rdmp_gym.dmp.settings.FitSettings`, default
    :data:`~rdmp_gym.dmp.settings.DEFAULT_FIT`): ``delta``, ``regularization``, ``method``, ``substeps``, ``smoothing``.
    Returns a copy of ``dmp`` with ``ending`` set."""
    _check_stop_settings(n_stop, nu1_factor, nu2_factor)
    fit = FitSettings.resolve(settings)
    delta, regularization, method, substeps, smoothing = (fit.delta, fit.regularization, fit.method,
                                                           int(fit.substeps), fit.smoothing)
    if regularization is None:          # resolved per method, as in RhythmicDMP.fit
        regularization = 1e-4 if method == "trajectory" else 1e-6
    dt = demo.dt
    canonical, mu = dmp.canonical, dmp.canonical.mu
    fading = StopFading(nu1_factor * mu, nu2_factor * mu, delta=delta)
    u1 = minimum_jerk_inverse(1.0 - nu1_factor)
    u2 = minimum_jerk_inverse(1.0 - nu2_factor)
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
