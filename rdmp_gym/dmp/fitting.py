"""Imitation: fitting a rhythmic DMP to demonstrations (:func:`fit_rhythmic`), and the regressions it uses.

:func:`fit_rhythmic` is the whole fit behind :meth:`RhythmicDMP.fit <rdmp_gym.dmp.rhythmic.RhythmicDMP.fit>`:
segmentation, the canonical system, the basis functions along each transient's canonical path, the smoothness penalty,
and one of three regressions of the weights (the formulation is in :mod:`rdmp_gym.dmp.basis` and
:mod:`rdmp_gym.dmp.canonical`, the rollout in :mod:`rdmp_gym.dmp.rhythmic`):

* ``lwr``: locally weighted regression exactly as the paper's (11)/(12): each weight is the
  activation-weighted mean of the target, one basis function at a time.
* ``ridge``: beyond the paper, one regularised least-squares problem on the normalised basis, so the
  mixture (5) itself (not each basis function separately) fits the target; all weights at once.
* ``trajectory`` (the default of :meth:`RhythmicDMP.fit`): beyond the paper, the weights and the start
  state that make the DMP's own rollout match the sampled positions, with a second-difference
  smoothness penalty on neighbouring weights. It needs no derivatives of the noisy samples: the
  target (10) multiplies position noise by ``alpha_z beta_z`` and the acceleration estimate amplifies it
  further, and every forcing error above the spring's bandwidth reaches the acceleration unfiltered.
"""

from __future__ import annotations

import itertools
import logging
from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np

from ..signals.demonstrations import Demonstration
from ..signals.filters import smooth_derivatives
from ..signals.segmentation import Segmentation, phase_shift, segment
from ..validation import check_count, check_nonnegative, check_positive
from .basis import (
    NORMALISATION_EPSILON,
    BasisSet,
    Fading,
    normalize,
    periodic_width,
    transient_basis_along_path,
    transient_times,
    von_mises,
)
from .canonical import CanonicalSystem
from .settings import (
    DEFAULT_FIT,
    FIT_METHODS,
    HANDOVER_FLOOR,
    HANDOVERS,
    PAPER_FIT,
    PRIORS,
    PUBLISHED_ENV_FIT,
    FitSettings,
)
from .start import TransientStart, settled_state, start_blend_profiles
from .transformation import cached_system

__all__ = [
    "DEFAULT_FIT",
    "FADE_BEFORE_T",
    "FIT_METHODS",
    "HANDOVERS",
    "HANDOVER_FLOOR",
    "JOIN_FLOOR",
    "PAPER_FIT",
    "PAPER_SETTINGS",
    "PRIORS",
    "PUBLISHED_ENV_FIT",
    "SMOOTHNESS_CANDIDATES",
    "SMOOTHNESS_REFERENCE",
    "START_PRIOR",
    "FitSettings",
    "FittedDMP",
    "cross_validation_score",
    "fit_rhythmic",
    "fit_trajectory",
    "fit_weights",
    "forcing_target",
    "join_relief",
    "relative_to_pattern",
    "second_differences",
    "trajectory_design",
]

logger = logging.getLogger(__name__)


def forcing_target(Y: np.ndarray, Yd: np.ndarray, Ydd: np.ndarray, anchor: np.ndarray, omega: float,
                   alpha_z: float) -> np.ndarray:
    """Eq. (10): ``f = ydd / Omega^2 - alpha_z (beta_z (g - y) - yd / Omega)``, all ``[L, d]``."""
    beta_z = alpha_z / 4.0
    return Ydd / omega**2 - alpha_z * (beta_z * (anchor - Y) - Yd / omega)


def second_differences(sizes: Sequence[int], cyclic: Sequence[bool], spacings: Sequence[float],
                       reference: float) -> np.ndarray:
    """Second-difference operator ``[R, D]`` over consecutive families of ``sizes`` weights (D = sum).

    Row ``(w[i-1] - 2 w[i] + w[i+1]) (h_0 / h)^1.5`` for neighbours within one family (a cyclic family also
    wraps around), ``h`` the family's spacing in time and ``h_0 = reference``: the sum of squares then
    approximates the same integral of the squared second time derivative of the weights for every family,
    whatever its spacing or number of basis functions.
    """
    rows = []
    offset = 0
    for size, wraps, spacing in zip(sizes, cyclic, spacings, strict=True):
        centres = range(size) if wraps else range(1, size - 1)
        gain = (reference / spacing) ** 1.5
        for i in centres:
            row = np.zeros(sum(sizes))
            row[offset + (i - 1) % size] += gain
            row[offset + i] -= 2.0 * gain
            row[offset + (i + 1) % size] += gain
            rows.append(row)
        offset += size
    return np.array(rows).reshape(-1, sum(sizes))


def fit_weights(activations: np.ndarray, target: np.ndarray, method: str = "ridge",
                regularization: float = 1e-6, smoothness: float = 0.0,
                differences: np.ndarray | None = None, floor: float = NORMALISATION_EPSILON) -> np.ndarray:
    """Weights ``W [D, d]`` from raw activations ``[L, D]`` and forcing targets ``[L, d]`` (eq. (10)).

    ``regularization`` and ``smoothness`` (ridge only) penalise ``w`` and ``differences @ w`` (see
    :func:`second_differences`), relative to the mean diagonal of the normal matrix; ``floor`` is the
    mixture's (see :class:`~rdmp_gym.dmp.basis.Fading`). A basis function that is never active gets weight 0
    under either method.
    """
    if isinstance(regularization, bool) or not isinstance(regularization, (int, float, np.integer, np.floating)) \
            or not 0.0 <= regularization < np.inf:
        raise ValueError(f"regularization: expected a finite number >= 0, got {regularization!r}")
    if method == "lwr":
        mass = activations.sum(axis=0)                                          # [D]
        active = mass > 1e-12 * max(float(mass.max()), 1e-300)
        weights = np.zeros((activations.shape[1], target.shape[1]))
        weights[active] = (activations[:, active].T @ target) / mass[active, None]
        return weights
    if method == "ridge":
        normalized = normalize(activations, floor)
        gram = normalized.T @ normalized
        scale = max(float(np.mean(np.diag(gram))), 1e-300)
        penalty = regularization * scale * np.eye(gram.shape[0])
        if smoothness > 0.0 and differences is not None:
            penalty = penalty + smoothness * scale * differences.T @ differences
        return np.linalg.solve(gram + penalty, normalized.T @ target)
    raise ValueError(f"method: expected one of {FIT_METHODS}, got {method!r}")


def fit_trajectory(responses: Sequence[np.ndarray], start_columns: Sequence[np.ndarray],
                   samples: Sequence[np.ndarray], differences: np.ndarray | Sequence[np.ndarray],
                   smoothness: float | Sequence, regularization: float = 1e-8,
                   start_penalties: Sequence[Sequence[float]] = ()) -> tuple[np.ndarray, np.ndarray]:
    """Weights and start states that make the DMP's own rollout match the sampled positions.

    The rollout is linear in the weights and in each demonstration's start: ``y(t) = sum_b w_b R_b(t) +
    sum_c s_c S_c(t)`` (``R_b``: the path's response to basis function b alone, ``S_c``: to the start
    values ``s_c``). One penalised least-squares problem over all demonstrations gives the weights (shared)
    and each demonstration's start values (its own), without differentiating the noisy samples.

    Args:
        responses: per demonstration k, ``[L_k, D]`` responses to each basis function at its samples.
        start_columns: per demonstration, ``[L_k, C]`` responses to its C start values.
        samples: per demonstration, ``[L_k, d]`` positions minus the part the anchor explains.
        differences: ``[R, D]`` second-difference operator of :func:`second_differences`, or several (e.g. one
            per basis family), each with its own weight.
        smoothness: the penalty on ``differences @ w`` (one number for every operator, or one entry per operator);
            an entry may be a sequence of candidates: the combination of least generalised cross-validation score
            (:func:`cross_validation_score`) is used.
        regularization: penalty on ``w``. All relative to the mean diagonal of the normal matrix of the weights.
        start_penalties: candidates, each ``[C]`` penalties pulling the start values towards 0, relative to their
            columns' diagonal of the normal matrix: the smoothness is chosen under the first, then the candidate of
            least score at that smoothness is used (no pull when empty).
    Returns:
        ``(W [D, d], starts [K, C, d])``.
    """
    n_basis, n_demos = responses[0].shape[1], len(samples)
    design, right = _stacked_design(responses, start_columns), np.concatenate(samples)
    gram, moments = design.T @ design, design.T @ right
    scale = max(float(np.mean(np.diag(gram)[:n_basis])), 1e-300)
    pulls = [np.tile(np.asarray(penalty, dtype=float), n_demos) * np.diag(gram)[n_basis:]
             for penalty in start_penalties] or [np.zeros(gram.shape[0] - n_basis)]
    operators = [differences] if isinstance(differences, np.ndarray) else list(differences)
    curvatures = [operator.T @ operator for operator in operators]

    def normal_matrix(weights: tuple[float, ...], pull: np.ndarray) -> np.ndarray:
        matrix = gram.copy()
        matrix[:n_basis, :n_basis] += scale * (sum(w * curvature for w, curvature in zip(weights, curvatures,
                                                                                           strict=True))
                                               + regularization * np.eye(n_basis))
        matrix[n_basis:, n_basis:] += np.diag(pull)
        return matrix

    energy = float(np.sum(right**2))

    def score(weights: tuple[float, ...], pull: np.ndarray) -> float:
        return cross_validation_score(normal_matrix(weights, pull), gram, moments, energy, right.size)

    candidates = list(itertools.product(*_smoothness_grids(smoothness, len(operators))))
    chosen = candidates[0] if len(candidates) == 1 else min(candidates, key=lambda weights: score(weights, pulls[0]))
    pull = pulls[0] if len(pulls) == 1 else min(pulls, key=lambda candidate: score(chosen, candidate))
    if len(candidates) > 1:
        logger.info("smoothness %s chosen by generalised cross-validation", [f"{w:.3g}" for w in chosen])
    solution = np.linalg.solve(normal_matrix(chosen, pull), moments)
    return solution[:n_basis], solution[n_basis:].reshape(n_demos, start_columns[0].shape[1], -1)


def _stacked_design(responses: Sequence[np.ndarray], start_columns: Sequence[np.ndarray]) -> np.ndarray:
    """The design ``[sum L_k, D + K C]`` of :func:`fit_trajectory`: the shared weights' responses, then each
    demonstration's start columns in its own block."""
    n_basis, n_start = responses[0].shape[1], start_columns[0].shape[1]
    rows = []
    for k, (response, columns) in enumerate(zip(responses, start_columns, strict=True)):
        design = np.zeros((response.shape[0], n_basis + n_start * len(responses)))
        design[:, :n_basis] = response
        design[:, n_basis + n_start * k: n_basis + n_start * (k + 1)] = columns
        rows.append(design)
    return np.concatenate(rows)


def cross_validation_score(normal_matrix: np.ndarray, gram: np.ndarray, moments: np.ndarray, energy: float,
                           n_values: int) -> float:
    """Generalised cross-validation score of the penalised least squares ``normal_matrix @ x = moments``
    (``moments = A.T @ b``, ``gram = A.T @ A``, ``energy = |b|^2`` over ``n_values`` entries of ``b [L, d]``): the
    mean squared residual over ``(1 - dof / L)^2``, ``dof`` the trace of the hat matrix. It estimates the error on
    unseen samples (Craven and Wahba 1979), so the penalty it prefers is about the least that keeps the noise out:
    weak on clean samples, stronger on noisy ones."""
    both = np.linalg.solve(normal_matrix, np.concatenate([moments, gram], axis=1))       # one factorisation
    solution, hat = both[:, : moments.shape[1]], both[:, moments.shape[1]:]
    residual = (energy - 2.0 * np.sum(solution * moments) + np.sum(solution * (gram @ solution))) / n_values
    n_rows = n_values / moments.shape[1]
    dof = float(np.trace(hat))
    return float(residual) / (1.0 - dof / n_rows) ** 2


def _smoothness_grids(smoothness: float | Sequence, n_operators: int) -> list[tuple[float, ...]]:
    """Per penalty operator, the candidate weights: a number applies to every operator; a sequence gives each
    operator a number or a sequence of candidates."""
    if np.isscalar(smoothness) or getattr(smoothness, "ndim", 1) == 0:
        return [(float(smoothness),)] * n_operators
    if len(smoothness) != n_operators:
        raise ValueError(f"smoothness: expected a number or {n_operators} entries, got {len(smoothness)}")
    return [tuple(float(w) for w in np.atleast_1d(entry)) for entry in smoothness]


# ------------------------------------------------------------------ the rhythmic DMP's fit

MIN_TRANSIENT = 0.05
"""The shortest transient :func:`fit_rhythmic` encodes, as a fraction of the period."""

SMOOTHNESS_REFERENCE = 40
"""``smoothness`` is calibrated for this many periodic basis functions per period (the time spacing
``period / 40``); other spacings get the penalty on the same time curvature."""

JOIN_FLOOR = 0.1
"""The share of the transient smoothness penalty that :func:`fit_rhythmic` keeps at T (``join_width``): a C2 join's
acceleration has a corner there (its jerk jumps by up to 170 m/s^3 on the test joins), which the full penalty rounds
off over several basis spacings."""

START_PRIOR = 0.01
"""The pull of the fitted start velocity towards rest that :func:`fit_rhythmic` tries (``start_prior="auto"``), relative
to its column of the normal matrix. The start velocity's blend profile spans the whole transient, so a free start
velocity trades against the first weights and absorbs misfit anywhere in the transient: 49-83 mm/s fitted on C2 joins
that start at rest, from noise-free samples too, with a spike of acceleration after the start (1.3 mm/s pulled)."""

SMOOTHNESS_CANDIDATES = tuple(float(value) for value in np.logspace(np.log10(0.15), 1.0, 16))
"""The smoothness penalties among which :func:`fit_rhythmic` chooses, for each family, by generalised
cross-validation (``smoothness="auto"``, trajectory fit): 0.15 to 10. The lower end keeps the noise out of the
transient near the hand-over (0.1: the worst 0.2 s window of one C2 join rose from 19.2 % to 20.8 %; 1e-4, one
penalty for both families: the peak acceleration from canonical starts off the encoded path reached 7.7x the
demonstration's on noise-free samples)."""

PAPER_SETTINGS = PAPER_FIT.changes()
"""Keywords of :func:`fit_rhythmic` that give :data:`~rdmp_gym.dmp.settings.PAPER_FIT` (the paper's formulation as first
implemented here); ``{**PAPER_SETTINGS, "method": "ridge"}`` fits the same basis by global least squares."""

FADE_BEFORE_T = PUBLISHED_ENV_FIT.changes(exclude=("n_periodic", "n_transient", "method"))
"""Keywords of :func:`fit_rhythmic` for the fade over the ``t_f`` before T, the first transient centre at the start,
a plain second-difference penalty of fixed weight 0.3, not relaxed about T, a free start velocity and the mixture's
floor of 1 %: :data:`~rdmp_gym.dmp.settings.PUBLISHED_ENV_FIT` but for the numbers of basis functions and the method."""


class FittedDMP(NamedTuple):
    """The parts of a fitted :class:`~rdmp_gym.dmp.rhythmic.RhythmicDMP`, in its constructor's order."""

    canonical: CanonicalSystem
    basis: BasisSet
    weights: np.ndarray                 # [d, D]
    transients: list[TransientStart]
    anchor: np.ndarray                  # [d]
    alpha_z: float


def relative_to_pattern(differences: np.ndarray, n_periodic: int, pattern: np.ndarray, shares: np.ndarray
                        ) -> np.ndarray:
    """The penalty rows ``[R, D]`` with each transient weight taken relative to its share of the periodic forcing.

    A row acts on ``w_t - shares * (pattern @ w_p)`` instead of ``w_t`` (``w_p``: the N periodic weights first,
    ``w_t``: the transient ones; ``pattern [M, N]``: the periodic mixture at each transient centre's phase;
    ``shares [M]`` in [0, 1]). Rows on the periodic weights alone are unchanged.
    """
    relative = differences.copy()
    relative[:, :n_periodic] -= differences[:, n_periodic:] @ (shares[:, None] * pattern)
    return relative


def fit_rhythmic(demos: Demonstration | Sequence[Demonstration], n_periodic: int | None = None,
                 n_transient: int | Sequence[int] | None = None, method: str | None = None, *,
                 settings: FitSettings | None = None, segmentations: Sequence[Segmentation] | None = None,
                 period: float | None = None, **changes: Any) -> FittedDMP:
    """Fit a DMP to one or more demonstrations that share a periodic pattern (paper III-E, V-A).

    :meth:`RhythmicDMP.fit <rdmp_gym.dmp.rhythmic.RhythmicDMP.fit>` calls this and builds the DMP from its parts.

    Args:
        demos: a :class:`Demonstration` or K of them (one transient each), all with d dimensions.
        n_periodic, n_transient, method: the most used settings, by position (``None``: as ``settings`` say).
        settings: the fit's settings (:class:`~rdmp_gym.dmp.settings.FitSettings`, which documents each; default
            :data:`~rdmp_gym.dmp.settings.DEFAULT_FIT`).
        segmentations: per demonstration; estimated with :func:`~rdmp_gym.signals.segmentation.segment` when omitted.
        period: common period (s); the mean of the segmentations' periods when omitted.
        changes: settings by name, over ``settings`` (``alpha_z=25.0``, ``smoothness=0.3``, ...).
    """
    demos = _as_demos(demos)
    fit = FitSettings.resolve(settings, n_periodic=n_periodic, n_transient=n_transient, method=method, **changes)
    regularization, smoothness = _check_settings(fit)
    start_penalties = ([(0.0, 0.0), (0.0, START_PRIOR)] if isinstance(fit.start_prior, str)
                       and fit.start_prior == "auto" else [(0.0, check_nonnegative(fit.start_prior, "start_prior"))])
    join_width = check_nonnegative(fit.join_width, "join_width")
    n_periodic = check_count(fit.n_periodic, "n_periodic", 2)
    sizes = _transient_sizes(fit.n_transient, len(demos))
    segmentations, common_period = _segmentations(demos, segmentations, period)
    canonical = CanonicalSystem(common_period, mu=fit.mu, eta=fit.eta, alpha=fit.alpha, beta=fit.beta)
    anchor = np.mean([seg.anchor for seg in segmentations], axis=0)
    lengths = [seg.transient_length for seg in segmentations]
    entrance = _entrance_phases(canonical, demos, segmentations)
    mu1 = fit.mu1_factor * fit.mu
    t_f = (check_positive(fit.fading_time, "fading_time") if fit.fading_time is not None
           else min(fit.fading_fractions[0] * common_period, fit.fading_fractions[1] * min(lengths)))
    if t_f >= min(lengths):
        raise ValueError(f"fading_time: must be shorter than the shortest transient ({min(lengths):.3g} s)")
    fading = Fading(mu1=mu1, mu2=canonical.init_T(t_f, 0.0, mu1)[1], delta=fit.delta, floor=fit.floor)
    late = t_f if fit.handover == "after" else 0.0          # the canonical state reaches mu1 at T + late
    inits = [canonical.init_T(length + late, phase + canonical.omega * late, mu1)
             for length, phase in zip(lengths, entrance, strict=True)]
    spans = [length + late - 0.5 * t_f for length in lengths]        # the last transient centre
    times = [transient_times(span, m, fit.transient_lead) for span, m in zip(spans, sizes, strict=True)]
    paths = [transient_basis_along_path(canonical, phi0, r0, span, m, fit.transient_overlap, fit.turn_height,
                                        fit.transient_lead)
             for (phi0, r0), span, m in zip(inits, spans, sizes, strict=True)]
    basis = BasisSet(periodic_centres=2.0 * np.pi * np.arange(n_periodic) / n_periodic,
                     periodic_widths=np.full(n_periodic, periodic_width(n_periodic, fit.periodic_overlap)),
                     transient_centres=np.concatenate([centres for centres, _ in paths]),
                     transient_widths=np.concatenate([widths for _, widths in paths]),
                     transient_sizes=tuple(sizes), fading=fading)
    differences = _penalty(basis, times, lengths, common_period, fit.prior, join_width)
    weights, starts = _regression(fit, demos, canonical, basis, inits, lengths, anchor, smoothness, regularization,
                                  differences, start_penalties)
    transients = [TransientStart(phi0, r0, length, phase, y0.copy(), yd0.copy())
                  for (phi0, r0), length, phase, (y0, yd0) in zip(inits, lengths, entrance, starts, strict=True)]
    logger.info("fitted %d transient(s), N=%d, M=%s, period %.4g s, method %s",
                len(demos), n_periodic, sizes, common_period, fit.method)
    return FittedDMP(canonical, basis, weights.T, transients, anchor, fit.alpha_z)


def _transient_sizes(n_transient: int | Sequence[int], n_demos: int) -> list[int]:
    """The transient basis functions per demonstration: an int for all, or one per demonstration."""
    sizes = ([check_count(n_transient, "n_transient", 1)] * n_demos if np.ndim(n_transient) == 0
             else [check_count(m, "n_transient", 1) for m in n_transient])
    if len(sizes) != n_demos:
        raise ValueError(f"n_transient: expected a positive int or {n_demos} positive ints, got {n_transient!r}")
    return sizes


def _as_demos(demos: Demonstration | Sequence[Demonstration]) -> list[Demonstration]:
    demos = [demos] if isinstance(demos, Demonstration) else list(demos)
    if not demos:
        raise ValueError("demos: expected at least one Demonstration")
    for index, demo in enumerate(demos):
        if not isinstance(demo, Demonstration):
            raise TypeError(f"demos[{index}]: expected a Demonstration, got {type(demo).__name__}")
        if demo.n_dims != demos[0].n_dims:
            raise ValueError(f"demos[{index}]: has {demo.n_dims} dimensions, demos[0] has {demos[0].n_dims}")
    return demos


def _check_settings(fit: FitSettings) -> tuple[float, float | tuple]:
    """Refuse bad settings of :func:`fit_rhythmic`; returns the regularization and the smoothness (or its
    candidates), their defaults resolved per method."""
    method, regularization, handover, prior, turn_height = (fit.method, fit.regularization, fit.handover, fit.prior,
                                                            fit.turn_height)
    if method not in FIT_METHODS:
        raise ValueError(f"method: expected one of {FIT_METHODS}, got {method!r}")
    if handover not in HANDOVERS:
        raise ValueError(f"handover: expected one of {HANDOVERS}, got {handover!r}")
    if prior not in PRIORS:
        raise ValueError(f"prior: expected one of {PRIORS}, got {prior!r}")
    if not 0.0 < turn_height < 1.0:
        raise ValueError(f"turn_height: must lie in (0, 1), got {turn_height!r}")
    smoothness = _smoothness_setting(fit.smoothness, method)
    check_positive(fit.smoothing, "smoothing")
    check_positive(fit.alpha_z, "alpha_z")
    if regularization is None:
        regularization = 1e-4 if method == "trajectory" else 1e-6
    return check_nonnegative(regularization, "regularization"), smoothness


def _smoothness_setting(smoothness: float | str | Sequence, method: str) -> float | tuple:
    """``smoothness`` of :func:`fit_rhythmic` as :func:`fit_trajectory` takes it: a number, or per family
    (periodic, transient) a tuple of candidates (``"auto"``: :data:`SMOOTHNESS_CANDIDATES`)."""
    if isinstance(smoothness, str) and smoothness == "auto":
        return (SMOOTHNESS_CANDIDATES,) * 2 if method == "trajectory" else 0.3
    if isinstance(smoothness, Sequence) and not isinstance(smoothness, str):
        if method != "trajectory" or len(smoothness) != 2:
            raise ValueError(f"smoothness: a (periodic, transient) pair needs method='trajectory' and two entries, "
                             f"got {smoothness!r} with method={method!r}")
        return tuple(SMOOTHNESS_CANDIDATES if isinstance(entry, str) and entry == "auto"
                     else (_smoothness_number(entry),) for entry in smoothness)
    return _smoothness_number(smoothness)


def _smoothness_number(value: object) -> float:
    if isinstance(value, str) or np.ndim(value) != 0:
        raise ValueError(f"smoothness: expected a number >= 0, 'auto' or a (periodic, transient) pair of them, "
                         f"got {value!r}")
    return check_nonnegative(value, "smoothness")


def _segmentations(demos: list[Demonstration], segmentations: Sequence[Segmentation] | None, period: float | None
                   ) -> tuple[list[Segmentation], float]:
    """One segmentation per demonstration (estimated when omitted) and the common period (s)."""
    if segmentations is None:
        segmentations = [segment(demo, period=period) for demo in demos]
    elif len(segmentations) != len(demos):
        raise ValueError(f"segmentations: expected {len(demos)}, got {len(segmentations)}")
    common_period = (check_positive(period, "period") if period is not None
                     else float(np.mean([seg.period for seg in segmentations])))
    for k, (demo, seg) in enumerate(zip(demos, segmentations, strict=True)):
        if seg.transient_length < max(MIN_TRANSIENT * seg.period, demo.dt):
            raise ValueError(f"demos[{k}]: {demo.name or 'the demonstration'} is periodic from its first samples "
                             f"(transient {seg.transient_length:.3g} s, period {seg.period:.3g} s): this DMP "
                             "encodes a start from rest into the pattern, so record the approach too, or use "
                             "rdmp_gym.PeriodicDMP for a purely periodic movement")
    return list(segmentations), common_period


def _entrance_phases(canonical: CanonicalSystem, demos: list[Demonstration], segmentations: list[Segmentation]
                     ) -> list[float]:
    """The phase (rad) at which each transient enters the pattern, relative to the shortest transient's."""
    lengths = [seg.transient_length for seg in segmentations]
    reference = int(np.argmin(lengths))
    return [canonical.omega * phase_shift(demos[reference], segmentations[reference], demo, seg, canonical.period)
            if k != reference else 0.0 for k, (demo, seg) in enumerate(zip(demos, segmentations, strict=True))]


def _penalty(basis: BasisSet, times: list[np.ndarray], lengths: list[float], period: float, prior: str,
             join_width: float) -> list[np.ndarray]:
    """The smoothness penalty's rows: second differences of each family's weights (see :func:`second_differences`),
    the transient ones relative to the pattern under ``prior="pattern"`` (:func:`relative_to_pattern`, with the start
    blend's progress ``1 - P0(t_j)`` at the centre times ``times``) and relaxed about T (:func:`join_relief`); as
    ``[rows on the periodic weights [R_p, D], rows on the transient ones [R_t, D]]``."""
    n_periodic = basis.n_periodic
    spacings = [period / n_periodic] + [float(np.ptp(t)) / max(t.size - 1, 1) for t in times]
    differences = second_differences((n_periodic, *basis.transient_sizes), (True,) + (False,) * len(times),
                                     spacings, period / SMOOTHNESS_REFERENCE)
    periodic = ~np.any(differences[:, n_periodic:], axis=1)
    relief = np.concatenate([join_relief(t[1:-1], length, join_width) for t, length in zip(times, lengths,
                                                                                           strict=True)])
    if prior == "flat":
        return [differences[periodic], np.sqrt(relief)[:, None] * differences[~periodic]]
    phases = np.arctan2(basis.transient_centres[:, 1], basis.transient_centres[:, 0])
    pattern = normalize(von_mises(phases, basis.periodic_centres, basis.periodic_widths), basis.fading.floor)
    shares = np.concatenate([1.0 - start_blend_profiles(t, length)[0, 0] for t, length in zip(times, lengths,
                                                                                              strict=True)])
    relative = relative_to_pattern(differences, n_periodic, pattern, shares)
    return [relative[periodic], np.sqrt(relief)[:, None] * relative[~periodic]]


def join_relief(times: np.ndarray, length: float, width: float) -> np.ndarray:
    """Weights ``[M]`` of the transient penalty's rows centred at ``times [M]`` (s): ``1 - (1 - JOIN_FLOOR)
    exp(-((t - T) / width)^2 / 2)``, down to :data:`JOIN_FLOOR` at T = ``length``, where a start planned to meet the
    moving pattern bends fastest (its jerk jumps); all 1 for ``width`` 0."""
    if width == 0.0:
        return np.ones_like(times)
    return 1.0 - (1.0 - JOIN_FLOOR) * np.exp(-0.5 * ((times - length) / width) ** 2)


def _regression(fit: FitSettings, demos: list[Demonstration], canonical: CanonicalSystem, basis: BasisSet,
                inits: list, lengths: list[float], anchor: np.ndarray, smoothness: float | tuple, regularization: float,
                differences: list[np.ndarray], start_penalties: list[tuple[float, float]]) -> tuple[np.ndarray, list]:
    """Weights ``[D, d]`` and per demonstration the start ``(y0 [d], yd0 [d])``, by ``method``: the trajectory fit
    (:func:`fit_trajectory`, the start pulled towards rest by one of ``start_penalties``), or ``lwr``/``ridge`` on
    the forcing target (10) (:func:`fit_weights`) with the smoothed start and the start velocity that best explains
    the samples under the smooth start (a derivative estimate at the first noisy sample is off by up to 0.1 m/s).
    ``smoothness`` and ``regularization``: ``fit``'s, resolved per method."""
    method, alpha_z = fit.method, fit.alpha_z
    responses, start_columns, samples = trajectory_design(canonical, basis, demos, inits, lengths, anchor, alpha_z,
                                                          fit.substeps)
    if method == "trajectory":
        weights, starts = fit_trajectory(responses, start_columns, samples, differences, smoothness, regularization,
                                         start_penalties)
        return weights, list(starts)
    activations, targets, smoothed_starts = _forcing_targets(demos, canonical, basis, inits, anchor, alpha_z,
                                                             fit.smoothing)
    weights = fit_weights(activations, targets, method, regularization, smoothness, np.concatenate(differences),
                          basis.fading.floor)
    starts = [(y0, np.linalg.lstsq(columns[:, 1:], sample - response @ weights - columns[:, :1] * y0,
                                   rcond=None)[0][0])
              for y0, response, columns, sample in zip(smoothed_starts, responses, start_columns, samples,
                                                       strict=True)]
    return weights, starts


def _forcing_targets(demos: list[Demonstration], canonical: CanonicalSystem, basis: BasisSet, inits: list,
                     anchor: np.ndarray, alpha_z: float, smoothing: float
                     ) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
    """The raw activations ``[L, D]`` and forcing targets (10) ``[L, d]`` of all smoothed demonstrations (stacked),
    and each demonstration's smoothed start ``[d]``."""
    activations, targets, starts = [], [], []
    for demo, (phi0, r0) in zip(demos, inits, strict=True):
        Y, Yd, Ydd = smooth_derivatives(demo.Y, demo.dt, smoothing)
        phi, r = canonical.state(demo.t - demo.t[0], phi0, r0)
        activations.append(basis.activations(phi, r))
        targets.append(forcing_target(Y, Yd, Ydd, anchor, canonical.omega, alpha_z))
        starts.append(Y[0])
    return np.concatenate(activations), np.concatenate(targets), starts


def trajectory_design(canonical: CanonicalSystem, basis: BasisSet, demos: Sequence[Demonstration],
                      inits: Sequence[tuple[float, float]], lengths: Sequence[float], anchor: np.ndarray,
                      alpha_z: float, substeps: int) -> tuple[list[np.ndarray], list[np.ndarray], list[np.ndarray]]:
    """The smooth-start rollout model ``y = P(t) + (y0 - P(0)) P0(t) + yd0 P1(t)`` at each demonstration's
    samples (P: the motion from the settled state, linear in the weights; P0, P1: the start-blend profiles),
    as ``(responses [L_k, D], start_columns [L_k, 2], samples minus the anchor's part [L_k, d])`` per
    demonstration. The basis responses are simulated ``substeps`` times finer than the samples."""
    responses, start_columns, samples = [], [], []
    for demo, (phi0, r0), length in zip(demos, inits, lengths, strict=True):
        phi, r = canonical.state(np.zeros(1), phi0, r0)
        settled, settled_yd = settled_state(basis.normalized(phi, r)[0], np.zeros(basis.n_basis), alpha_z)
        fine = np.arange((demo.n_samples - 1) * substeps + 1) * demo.dt / substeps
        phi, r = canonical.state(fine, phi0, r0)
        system = cached_system(canonical.omega, demo.dt / substeps, alpha_z)
        response = system.rollout(system.input(np.zeros(basis.n_basis), basis.normalized(phi, r)),
                                  settled, settled_yd / canonical.omega)[0][::substeps]  # [L, D]
        (fall, _, _), (slope, _, _) = start_blend_profiles(demo.t - demo.t[0], length)
        responses.append(response - fall[:, None] * settled - slope[:, None] * settled_yd)
        start_columns.append(np.stack([fall, slope], axis=1))
        samples.append(demo.Y - (1.0 - fall[:, None]) * anchor)
    return responses, start_columns, samples
