"""The fit's settings, defined once: :class:`FitSettings` and its named presets.

Every fit reads its defaults from here: :meth:`RhythmicDMP.fit <rdmp_gym.dmp.rhythmic.RhythmicDMP.fit>`,
:func:`~rdmp_gym.dmp.fitting.fit_rhythmic`, the stop's fit (:func:`~rdmp_gym.dmp.stopping.fit_ending`) and the whole
recording's (:func:`~rdmp_gym.recordings.recording_fit.fit_recording`). Three presets:

* :data:`DEFAULT_FIT`: the library's defaults (``FitSettings()``).
* :data:`PAPER_FIT`: the paper's formulation as first implemented here (LWR, a stiff spring, narrow basis functions).
* :data:`PUBLISHED_ENV_FIT`: the settings the published environments pin (the fade before T, N = M = 40, the
  trajectory fit), so that their tasks stay as published whatever the library's defaults.

    from rdmp_gym import RhythmicDMP, wiping_demonstration
    from rdmp_gym.dmp.settings import PAPER_FIT

    dmp = RhythmicDMP.fit(wiping_demonstration(1, rng=0), settings=PAPER_FIT.replace(method="ridge"))

The keyword form stays: ``RhythmicDMP.fit(demo, n_transient=30, smoothness=0.3)`` is
``settings=DEFAULT_FIT.replace(n_transient=30, smoothness=0.3)``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from .basis import NORMALISATION_EPSILON, SMOOTH_FLOOR

__all__ = ["DEFAULT_FIT", "FIT_METHODS", "HANDOVERS", "HANDOVER_FLOOR", "PAPER_FIT", "PRIORS", "PUBLISHED_ENV_FIT",
           "FitSettings"]

FIT_METHODS = ("lwr", "ridge", "trajectory")
"""The regressions of the fit (see :mod:`rdmp_gym.dmp.fitting`)."""

HANDOVERS = ("after", "before")
"""Where the fit puts the fade between the transient and the periodic family (``handover``)."""

PRIORS = ("pattern", "flat")
"""What the fit's smoothness penalty holds the transient weights to (``prior``)."""

HANDOVER_FLOOR = 0.3
"""The mixture's floor (:class:`~rdmp_gym.dmp.basis.Fading`) of the default fit: during the fade after T neither
family's activations sum to much, and a floor of 30 % of the sum on the encoded path makes the forcing term fade
smoothly off it (canonical starts off the encoded path: peak acceleration within 3x the demonstration's)."""


@dataclass(frozen=True)
class FitSettings:
    """Everything that chooses how a rhythmic DMP is fitted to demonstrations (not the demonstrations themselves,
    their segmentations or their period).

    Attributes:
        n_periodic: periodic basis functions N.
        n_transient: transient basis functions per transient (an int or one int per demonstration).
        method: ``"trajectory"`` (weights and start state that make the rollout itself match the samples, see
            :func:`~rdmp_gym.dmp.fitting.fit_trajectory`), ``"lwr"`` (the paper's (11)/(12)) or ``"ridge"`` (global
            least squares on the forcing target (10)).
        alpha_z: transformation-system gain (5: a softer spring, see the docs' design rationale; 25 in
            :data:`PAPER_FIT`).
        mu, eta, alpha, beta: canonical-system constants (the paper's defaults).
        mu1_factor: ``mu1 = mu1_factor * mu`` (1.2 in the paper).
        fading_time: t_f (s), the overlap of transient and periodic basis; ``None``: ``min(a period, b shortest
            transient)`` with ``(a, b) = fading_fractions``.
        delta: support threshold of the fades.
        periodic_overlap, transient_overlap: height at which neighbouring basis functions cross (0.8: wide,
            overlapping functions whose normalised mixture has no ripple at the basis spacing).
        smoothing: Savitzky-Golay window (s) for the demonstration's derivatives (``lwr``, ``ridge``).
        regularization: relative ridge penalty (``None``: 1e-4 for ``trajectory``, small weights, so the forcing term
            stays gentle off the encoded paths; 1e-6 otherwise).
        smoothness: relative penalty on second differences of neighbouring weights (``ridge``, ``trajectory``); 0 in
            :data:`PAPER_FIT`. ``"auto"``: for ``trajectory`` each family's penalty is chosen among
            :data:`~rdmp_gym.dmp.fitting.SMOOTHNESS_CANDIDATES` by generalised cross-validation
            (:func:`~rdmp_gym.dmp.fitting.cross_validation_score`), so it is as weak as the samples' noise allows and
            biases clean or well-determined parts little (C2 joins: transient acceleration error 10.2 % median
            against 11.2 % with 0.3); 0.3 for ``lwr`` and ``ridge``. A number fixes one penalty for both families:
            0.3 holds the periodic acceleration error of a small pure sinusoid under 0.35 mm noise below 10 % (0.1
            gave 10.0 %); 1 smooths fast approaches (15-22 %). A pair ``(periodic, transient)`` (``trajectory``
            only), each a number or ``"auto"``, sets each family's own.
        floor: added to the sum of activations in the mixture (5) (:class:`~rdmp_gym.dmp.basis.Fading`), so that the
            forcing term fades to 0 where no basis function is active.
        substeps: ``trajectory`` simulates each basis function's response this many times finer than the samples.
        fading_fractions: ``(a, b)`` of the default ``fading_time``.
        turn_height: the largest value a transient basis function may keep on the next turn of its spiral
            (:func:`~rdmp_gym.dmp.basis.transient_basis_along_path`; 1e-3 in :data:`PAPER_FIT`). Near the hand-over of a
            short period the turns are close, and a lower height narrows the last functions until gaps open between
            them: a ripple at the basis spacing (jerk up to 3x the true signal's).
        handover: where the transient family fades out and the periodic one fades in: ``"after"`` over the ``t_f``
            after T, where the demonstration is on its cycle; ``"before"`` over the ``t_f`` before T (the paper),
            where the mixture cannot follow a demonstration that is still off its cycle.
        transient_lead: spacings by which the first transient centre lies before the start
            (:func:`~rdmp_gym.dmp.basis.transient_times`; 0 in :data:`PAPER_FIT`).
        prior: what the smoothness penalty holds the transient weights to: ``"pattern"`` the periodic forcing at the
            centre's phase, in the share that the start blend has handed over to the pattern by the centre's time
            (0 at the start, 1 from T on), so the transient family can follow the pattern through the hand-over;
            ``"flat"``: plain second differences (straight lines).
        start_prior: ``trajectory`` only: a penalty pulling the fitted start velocity towards rest, relative to its
            column of the normal matrix (0: free). ``"auto"``: :data:`~rdmp_gym.dmp.fitting.START_PRIOR` or none,
            whichever has the lower generalised cross-validation score at the chosen smoothness (the pull on 28 of
            36 C2 joins that start at rest, none on 23 of 24 that start moving).
        join_width: the transient penalty's rows are relaxed about T (:func:`~rdmp_gym.dmp.fitting.join_relief`) over
            this many seconds (0: not at all).
    """

    n_periodic: int = 40
    n_transient: int | Sequence[int] = 44
    method: str = "trajectory"
    alpha_z: float = 5.0
    mu: float = 1.0
    eta: float = 35.0
    alpha: float = 1.0 / 6.0
    beta: float = 1.0 / 1000.0
    mu1_factor: float = 1.2
    fading_time: float | None = None
    delta: float = 1e-3
    periodic_overlap: float = 0.8
    transient_overlap: float = 0.8
    smoothing: float = 0.15
    regularization: float | None = None
    smoothness: float | str | Sequence = "auto"
    floor: float = HANDOVER_FLOOR
    substeps: int = 4
    fading_fractions: tuple[float, float] = (0.5, 0.25)
    turn_height: float = 0.3
    handover: str = "after"
    transient_lead: float = 2.0
    prior: str = "pattern"
    start_prior: float | str = "auto"
    join_width: float = 0.1

    @classmethod
    def names(cls) -> tuple[str, ...]:
        """The settings' names, in the order of the fields."""
        return tuple(field.name for field in dataclasses.fields(cls))

    def replace(self, **changes: Any) -> FitSettings:
        """A copy with ``changes``; an unknown name is a ``TypeError`` that lists the known ones."""
        unknown = sorted(set(changes) - set(self.names()))
        if unknown:
            raise TypeError(f"fit: unknown setting(s) {unknown}; FitSettings has {list(self.names())}")
        return dataclasses.replace(self, **changes)

    def changes(self, base: FitSettings | None = None, exclude: Sequence[str] = ()) -> dict[str, Any]:
        """The settings that differ from ``base`` (default: :data:`DEFAULT_FIT`), as keywords of the fit."""
        base = DEFAULT_FIT if base is None else base
        return {name: getattr(self, name) for name in self.names()
                if name not in exclude and _differs(getattr(self, name), getattr(base, name))}

    @classmethod
    def resolve(cls, settings: FitSettings | None = None, **changes: Any) -> FitSettings:
        """``settings`` (default :data:`DEFAULT_FIT`) with ``changes``; a change that is ``None`` for ``n_periodic``,
        ``n_transient`` or ``method`` keeps the setting (so positional ``None`` means "as the settings say")."""
        if settings is not None and not isinstance(settings, FitSettings):
            raise TypeError(f"settings: expected a FitSettings, got {type(settings).__name__}")
        kept = {name: value for name, value in changes.items()
                if not (value is None and name in ("n_periodic", "n_transient", "method"))}
        return (DEFAULT_FIT if settings is None else settings).replace(**kept)


def _differs(value: object, default: object) -> bool:
    return type(value) is not type(default) or value != default


DEFAULT_FIT = FitSettings()
"""The library's defaults: every fit that is given no settings."""

PAPER_FIT = FitSettings(method="lwr", n_transient=40, alpha_z=25.0, periodic_overlap=0.5, transient_overlap=0.5,
                        smoothness=0.0, floor=NORMALISATION_EPSILON, fading_fractions=(0.25, 0.25), turn_height=1e-3,
                        handover="before", transient_lead=0.0, prior="flat", start_prior=0.0, join_width=0.0)
"""The paper's formulation as first implemented here (LWR (11), a stiff spring, narrow basis functions, the bare
mixture (5), the families' fade before T, the first transient centre at the start); roll out with
``start_blend=False`` for the paper's start. ``PAPER_FIT.replace(method="ridge")`` fits the same basis by global least
squares."""

PUBLISHED_ENV_FIT = FitSettings(n_periodic=40, n_transient=40, method="trajectory", handover="before",
                                transient_lead=0.0, prior="flat", floor=SMOOTH_FLOOR, smoothness=0.3, start_prior=0.0,
                                join_width=0.0)
"""What the published environments fit their imitation DMP with: the fade over the ``t_f`` before T, the first
transient centre at the start, a plain second-difference penalty of fixed weight 0.3, not relaxed about T, a free
start velocity, the mixture's floor of 1 %, N = M = 40 and the trajectory fit. Their tasks stay as published
whatever the library's defaults."""
