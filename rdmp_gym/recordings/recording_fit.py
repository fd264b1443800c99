"""Fit a whole recording: the slow motion as the anchor's travel, the rhythm with a short entry, and the ending.

A person's recording (:func:`rdmp_gym.synthetic.demonstrations.realistic_recording` draws one) is a discrete motion
(rest, approach with pauses, drift of the working point, departure, rest) with a rhythm on top. Encoding the approach in
the paper's transient makes it seconds long: its canonical path starts far out (``r0`` in the hundreds) and its
many basis functions must shape the whole approach, which they do badly. Here the parts each get the mechanism
made for them:

* the slow part found by :func:`rdmp_gym.signals.segmentation.segment_rhythm` (approach, drift) is the anchor's discrete
  motion, a :class:`~rdmp_gym.dmp.sweep.Sweep` whose via points (every half second or period) are fitted to it by
  least squares (before the rhythm starts to grow, to the whole smoothed motion);
* the rhythm, relative to that moving anchor, is fitted by :meth:`RhythmicDMP.fit` from shortly before it starts
  to grow, so the paper's transient encodes only the entry into the rhythm; the canonical system then starts
  earlier on the same path, where no basis function is active yet (the forcing term is 0 there and the anchor's
  travel is the whole motion);
* the departure and the final rest are the stop of :mod:`rdmp_gym.dmp.stopping`
  (:func:`~rdmp_gym.dmp.stopping.fit_stop`).

:func:`recording_report` measures the result as a robot would execute it: the position error over the rhythm
against the recording's own cycle-to-cycle variation, the error at the start and at the final rest, and the peak
acceleration against the smoothed recording's.
"""

from __future__ import annotations

import itertools
import logging
from dataclasses import dataclass, replace

import numpy as np
from scipy.interpolate import CubicSpline

from ..dmp.ending import minimum_jerk_inverse
from ..dmp.fitting import (
    FADE_BEFORE_T,
    SMOOTHNESS_REFERENCE,
    fit_trajectory,
    second_differences,
    trajectory_design,
)
from ..dmp.rhythmic import RhythmicDMP
from ..dmp.settings import FitSettings
from ..dmp.stopping import fit_stop
from ..dmp.sweep import Sweep
from ..signals.demonstrations import Demonstration
from ..signals.filters import smooth_derivatives
from ..signals.segmentation import RhythmSegmentation, Segmentation, StopSegmentation, local_fit, segment_rhythm
from ..validation import check_positive

__all__ = ["ACCELERATION_SMOOTHING", "CONSTANT_RANGE", "ENTRY_PERIODS", "SMOOTHNESS", "RecordingFit",
           "constant_columns", "cycle_figures", "fit_recording", "normalise_tempo", "recording_report"]

logger = logging.getLogger(__name__)

ENTRY_PERIODS = 2.0
"""The entry into the rhythm that the paper's transient encodes, in periods before the full-size rhythm (1.5 left
its basis functions so close that a quick entry rang: 1.56x the clean peak)."""
_VIA_SPACING = 0.5          # s: the longest time between the anchor's via points
_PHASE_POINTS = 64          # samples per cycle when cycles are compared
#: s: the Savitzky-Golay window of the recording's acceleration (and of a pose recording's angular acceleration)
ACCELERATION_SMOOTHING = 0.15
CONSTANT_RANGE = 1e-12
"""A column of a recording whose range (largest minus smallest sample) is at most this, relative to its largest
magnitude where that exceeds 1, is constant (:func:`constant_columns`): rounding, not motion (an orientation held
level, written as the same quaternion with either sign, has tangent coordinates equal to ~1e-16)."""
SMOOTHNESS = 1.0
"""Weight smoothness of the fits: a person's entry into the rhythm has corners that 0.3 (RhythmicDMP.fit's default)
follows with up to 1.7x the recording's peak acceleration."""


@dataclass(frozen=True, eq=False)
class RecordingFit:
    """Result of :func:`fit_recording`.

    Attributes:
        dmp: the fitted DMP (anchor travel in ``dmp.sweep``, stop in ``dmp.ending`` when the recording ends).
        segmentation: where the rhythm and the rests were found.
        stop_at: the time (s from the start) to request the stop at to reproduce the recording; ``None`` without
            an ending.
    """

    dmp: RhythmicDMP
    segmentation: RhythmSegmentation
    stop_at: float | None

    def reproduce(self, t: np.ndarray) -> np.ndarray:
        """The reproduction ``[T, d]`` at even times ``t [T]`` (from the start of the recording)."""
        return self.dmp.rollout(t, stop_at=self.stop_at)


def _fit_sweep(demo: Demonstration, seg: RhythmSegmentation, anchor: np.ndarray, spacing: float,
               entry: float) -> Sweep:
    """The anchor's travel from the recording's onset to the rhythm's end, via points every ``spacing`` s fitted by
    least squares (minus ``anchor``) to the smoothed recording before ``entry`` (s; the whole motion is the anchor's
    there) and to its slow part from there to the rhythm's end."""
    t = demo.t - demo.t[0]
    smooth = smooth_derivatives(demo.Y, demo.dt, ACCELERATION_SMOOTHING)[0]
    target = np.where((t < entry)[:, None], smooth, seg.slow)
    n_points = max(int(np.ceil((seg.rhythm_end - seg.onset) / spacing)), 1)
    sweep = Sweep.uniform(seg.onset, seg.rhythm_end, n_points, demo.n_dims)
    rows = t <= seg.rhythm_end
    basis = sweep.basis(t[rows])
    gram = basis.T @ basis
    ridge = 1e-8 * max(float(np.trace(gram)) / n_points, 1e-300)
    points = np.linalg.solve(gram + ridge * np.eye(n_points), basis.T @ (target[rows] - anchor))
    return sweep.with_points(points)


def fit_recording(demo: Demonstration, *, period: float | None = None, start: float | None = None,
                  end: float | None = None, ending: bool | None = None, via_spacing: float | None = None,
                  n_periodic: int = 40, n_transient: int = 20, n_stop: int = 15, normalise: bool = True,
                  smoothness: float = SMOOTHNESS, timing_dims: int | None = None, **fit_kwargs) -> RecordingFit:
    """Fit a DMP to a whole recording: rest, approach, rhythm with a drifting working point, departure, rest.

    Args:
        demo: the recording on an even grid, outliers removed
            (:func:`rdmp_gym.signals.demonstrations.to_demonstration`).
        period, start, end: hints for :func:`rdmp_gym.signals.segmentation.segment_rhythm` (s; ``None``: detected).
        ending: fit the departure and the final rest as the DMP's stop (``None``: where the recording ends at rest;
            ``True`` raises if it does not).
        via_spacing: time between the anchor's via points (s; default one period, at most ``_VIA_SPACING``).
        n_periodic, n_transient, n_stop: basis functions of the rhythm, of its entry and of the stop.
        normalise: fit the recording with its cycles stretched to their mean period (:func:`normalise_tempo`).
        smoothness: penalty on second differences of neighbouring weights (see :meth:`RhythmicDMP.fit`).
        timing_dims: the first ``timing_dims`` columns set the timing (segmentation, tempo); the others ride along
            with their own slow part and weights (an orientation's tangent coordinates,
            :mod:`rdmp_gym.recordings.pose_fit`). ``None``: all columns.
        fit_kwargs: passed on to :meth:`RhythmicDMP.fit` (``method``, ``alpha_z``, ...), over the settings of
            :data:`~rdmp_gym.dmp.fitting.FADE_BEFORE_T` that the rhythm's entry is fitted with here.
    """
    if not isinstance(demo, Demonstration):
        raise TypeError(f"demo: expected a Demonstration, got {type(demo).__name__}")
    if "segmentations" in fit_kwargs:
        raise ValueError("segmentations: fit_recording segments the recording itself (give period/start/end)")
    seg = _segment(demo, timing_dims, period=period, start=start, end=end)
    if normalise:
        demo, original = normalise_tempo(demo, seg, timing_dims)
        start, end = (None if hint is None else float(np.interp(hint, original, demo.t - demo.t[0]))
                      for hint in (start, end))
        seg = _segment(demo, timing_dims, period=seg.period, start=start, end=end)
    spacing = min(seg.period, _VIA_SPACING) if via_spacing is None else check_positive(via_spacing, "via_spacing")
    t = demo.t - demo.t[0]
    first_rest = t <= max(seg.onset, demo.dt)
    anchor = demo.Y[first_rest].mean(axis=0)
    entry = max(seg.rhythm_start - ENTRY_PERIODS * seg.period, 0.0)
    # the anchor follows the whole motion only until the rhythm starts to grow: a rhythm that grows slowly (for
    # seconds before the encoded entry) would otherwise leave a step in its target and a jerk in the entry
    sweep = _fit_sweep(demo, seg, anchor, spacing, min(entry, seg.entry))

    rows = (t >= entry - 0.5 * demo.dt) & (t <= seg.rhythm_end + 0.5 * demo.dt)
    relative = demo.Y[rows] - sweep.offsets(t[rows])
    rhythm = Demonstration(t[rows] - t[rows][0], relative, name=demo.name)
    entry_length = seg.rhythm_start - t[rows][0]
    short = RhythmicDMP.fit(rhythm, n_periodic=n_periodic, n_transient=n_transient,
                            segmentations=[Segmentation(seg.period, entry_length, anchor)], period=seg.period,
                            **{**FADE_BEFORE_T, "smoothness": smoothness, **fit_kwargs})
    full = Demonstration(t[t <= seg.rhythm_end + 0.5 * demo.dt],
                         (demo.Y - sweep.offsets(t))[t <= seg.rhythm_end + 0.5 * demo.dt], name=demo.name)
    dmp = _delayed(short, full, seg.rhythm_start, entry_length, substeps=int(fit_kwargs.get("substeps", 4)),
                   smoothness=float(smoothness),
                   regularization=float(fit_kwargs.get("regularization") or 1e-4)).with_sweep(sweep)

    rest = seg.rest_time is not None
    if ending is True and not rest:
        raise ValueError("ending: the recording does not come to rest after its rhythm")
    stop_at = None
    if rest and ending is not False:
        goal = demo.Y[t >= seg.rest_time].mean(axis=0)
        stop_seg = StopSegmentation(Segmentation(seg.period, seg.rhythm_start, anchor), seg.rhythm_end,
                                    seg.rest_time, goal)
        dmp = fit_stop(dmp, demo, stop_seg, n_stop, settings=FitSettings.resolve(method="trajectory"))
        exit_at = _exit_time(dmp.ending, seg.rhythm_end)
        stop_at = exit_at - 0.5 * seg.period
    logger.info("fitted a recording: period %.4g s, entry %.3g s of %.3g s to the rhythm, %d via points, stop %s",
                seg.period, entry_length, seg.rhythm_start, sweep.n_points, stop_at)
    return RecordingFit(dmp=dmp, segmentation=seg, stop_at=stop_at)


def _segment(demo: Demonstration, timing_dims: int | None, **hints: float | None) -> RhythmSegmentation:
    """:func:`segment_rhythm` of the first ``timing_dims`` columns of ``demo`` (all for ``None``), with the slow
    part ``[L, d]`` of every column (the others' from :func:`local_fit` with the same period)."""
    if timing_dims is None or timing_dims == demo.n_dims:
        return segment_rhythm(demo, **hints)
    if not 0 < timing_dims < demo.n_dims:
        raise ValueError(f"timing_dims: expected a number of columns in [1, {demo.n_dims}], got {timing_dims!r}")
    seg = segment_rhythm(Demonstration(demo.t, demo.Y[:, :timing_dims], name=demo.name), **hints)
    riders = local_fit(Demonstration(demo.t, demo.Y[:, timing_dims:], name=demo.name), seg.period)[0]
    return replace(seg, slow=np.concatenate([seg.slow, riders], axis=1))


def _delayed(short: RhythmicDMP, full: Demonstration, rhythm_start: float, entry_length: float,
             substeps: int, smoothness: float, regularization: float) -> RhythmicDMP:
    """``short`` (fitted from shortly before the rhythm) started ``rhythm_start`` s before the rhythm: its canonical
    system starts earlier on the same path (``init_T(rhythm_start, ...)``), where no transient basis function is
    active yet, so the forcing term is 0 until the encoded entry begins. Weights and start state are fitted again
    (``trajectory``, :func:`~rdmp_gym.dmp.fitting.fit_trajectory`) to ``full``, the whole recording up to the rhythm's
    end, on that longer path and with the start blend over its length."""
    canonical, basis = short.canonical, short.basis
    transient = short.transients[0]
    phi0, r0 = canonical.init_T(rhythm_start, transient.entrance_phase, basis.fading.mu1)
    responses, start_columns, samples = trajectory_design(canonical, basis, [full], [(phi0, r0)], [rhythm_start],
                                                           short.anchor, short.alpha_z, substeps)
    n_transient = basis.transient_sizes[0]
    differences = second_differences((basis.n_periodic, n_transient), (True, False),
                                     [short.period / basis.n_periodic, entry_length / max(n_transient - 1, 1)],
                                     short.period / SMOOTHNESS_REFERENCE)
    weights, starts = fit_trajectory(responses, start_columns, samples, differences, smoothness, regularization)
    moved = replace(transient, phi0=phi0, r0=r0, length=rhythm_start, start=starts[0][0].copy(),
                    start_velocity=starts[0][1].copy())
    return RhythmicDMP(canonical, basis, weights.T, [moved], short.anchor, short.alpha_z, short.amplitude)


def _exit_time(ending, periodic_end: float, nu1_factor: float = 0.9, nu2_factor: float = 0.7) -> float:
    """The time (s) at which :func:`~rdmp_gym.dmp.stopping.fit_stop` placed the exit: the middle of the fade from the
    periodic to the stop family on the end of the periodic part."""
    u_mid = 0.5 * (minimum_jerk_inverse(1.0 - nu1_factor) + minimum_jerk_inverse(1.0 - nu2_factor))
    return periodic_end - u_mid * ending.length


def _cycle_cuts(t: np.ndarray, rhythmic: np.ndarray, period: float, start: float, end: float) -> np.ndarray:
    """Indices ``[C]`` where the cycles of ``rhythmic [L, d]`` between ``start`` and ``end`` (s) begin: crossings (at
    least 0.6 periods apart) of a level by its main direction. Upward crossings of its mean, unless another level
    or downward crossings (another phase) cut more whole cycles: a rhythm of 2.5 periods holds 2 whole cycles
    from some phase only."""
    inside = np.flatnonzero((t >= start) & (t <= end))
    signal = rhythmic[inside] - rhythmic[inside].mean(axis=0)
    along = signal @ np.linalg.svd(signal, full_matrices=False)[2][0]
    best = np.zeros(0, dtype=int)
    for sign, level in itertools.product((1.0, -1.0), np.append(0.0, np.quantile(along, [0.3, 0.7, 0.15, 0.85]))):
        shifted = sign * (along - level)
        cuts: list[int] = []
        for index in np.flatnonzero((shifted[:-1] < 0.0) & (shifted[1:] >= 0.0)):
            if not cuts or t[inside[index]] - t[inside[cuts[-1]]] >= 0.6 * period:
                cuts.append(int(index))
        if len(cuts) > best.size:
            best = np.array(cuts, dtype=int)
    return inside[best]


def _cycles(t: np.ndarray, rhythmic: np.ndarray, period: float, start: float, end: float) -> list[np.ndarray]:
    """The cycles ``[_PHASE_POINTS, d]`` of ``rhythmic [L, d]`` (centred on its mean between ``start`` and ``end``)
    cut at :func:`_cycle_cuts` and resampled in phase."""
    cuts = _cycle_cuts(t, rhythmic, period, start, end)
    inside = (t >= start) & (t <= end)
    signal = rhythmic - rhythmic[inside].mean(axis=0)
    grid = np.linspace(0.0, 1.0, _PHASE_POINTS, endpoint=False)
    return [np.stack([np.interp(t[a] + grid * (t[b] - t[a]), t, column) for column in signal.T], axis=1)
            for a, b in itertools.pairwise(cuts)]


def normalise_tempo(demo: Demonstration, seg: RhythmSegmentation, timing_dims: int | None = None
                    ) -> tuple[Demonstration, np.ndarray]:
    """``demo`` with the cycles of its rhythm stretched in time to their mean period, and the original time
    ``[L]`` (s from ``demo.t[0]``) of each of its samples; the cycles are cut on the first ``timing_dims`` columns
    (``None``: all).

    A person's period wanders from cycle to cycle; a least-squares fit of one constant-period pattern to the
    wandering cycles averages them out of phase and shrinks the pattern. Time is mapped by a smooth monotone
    function (a cubic spline through the cycle starts, moved onto an even spacing with the same first and last,
    and through the identity outside the rhythm), so the approach and the ending keep their timing.
    """
    t = demo.t - demo.t[0]
    cuts = t[_cycle_cuts(t, (demo.Y - seg.slow)[:, :timing_dims], seg.period, seg.rhythm_start, seg.rhythm_end)]
    if cuts.size < 3:
        return demo, t
    even = np.linspace(cuts[0], cuts[-1], cuts.size)
    before = np.arange(cuts[0] - seg.period, 0.0, -seg.period)[::-1]
    after = np.arange(cuts[-1] + seg.period, t[-1], seg.period)
    source = np.concatenate([[0.0], before[before > 0.5 * seg.period], cuts,
                             after[after < t[-1] - 0.5 * seg.period], [t[-1]]])
    target = np.concatenate([source[source < cuts[0]], even, source[source > cuts[-1]]])
    original = CubicSpline(target, source)(t)
    if np.any(np.diff(original) <= 0.0):
        return demo, t
    samples = CubicSpline(t, demo.Y, axis=0)(original)
    return Demonstration(demo.t, samples, name=demo.name), original


def recording_report(demo: Demonstration, result: RecordingFit) -> dict[str, float | None]:
    """How well ``result`` reproduces ``demo`` (m, m/s^2; times from ``demo.t[0]``).

    Keys: ``cycle_variation`` (RMS deviation of the recording's cycles from its mean cycle, relative to the slow
    part, times ``sqrt(n / (n - 1))`` for n cycles: the deviation from a mean of the same cycles is biased low),
    ``cycle_error`` (RMS deviation of the recording's cycles from the reproduction's mean cycle, cut the same
    way), ``error_ratio`` (their ratio: 1 when the reproduction's cycle is the recording's mean cycle),
    ``rhythm_rmse`` (plain RMS position error over the rhythm, including the drift of the person's timing),
    ``start_error`` (at the first sample), ``rest_error`` (mean over the final rest; ``None`` without one),
    ``peak_acceleration``, ``recording_peak_acceleration`` (Savitzky-Golay over ``ACCELERATION_SMOOTHING`` s) and
    ``acceleration_ratio``.

    A recording of which no column moves (:func:`constant_columns`: an orientation held level) has no cycles: its
    ``cycle_variation`` is 0 and its ``cycle_error`` the RMS of the reproduction's motion about its mean over the
    rhythm (0 when the DMP holds it still, as its anchor does).
    """
    seg = result.segmentation
    t = demo.t - demo.t[0]
    slow = local_fit(demo, seg.period)[0]
    reproduction = result.reproduce(demo.t)
    fine = np.arange(0.0, t[-1], 1e-3)
    acceleration = np.diff(result.reproduce(fine), 2, axis=0) / 1e-6
    recorded = smooth_derivatives(demo.Y, demo.dt, ACCELERATION_SMOOTHING)[2]
    if len(constant_columns(demo.Y)) == demo.n_dims:    # nothing moves: no cycles to cut (the anchor holds it)
        variation, error = 0.0, _still_error(t, reproduction, seg.rhythm_start, seg.rhythm_end)
    else:
        variation, error = cycle_figures(t, demo.Y - slow, reproduction - slow, seg.period, seg.rhythm_start,
                                         seg.rhythm_end)
    rhythm = (t >= seg.rhythm_start) & (t <= seg.rhythm_end)
    peak, recorded_peak = (float(np.max(np.linalg.norm(a, axis=1))) for a in (acceleration, recorded))
    rest = t >= seg.rest_time if seg.rest_time is not None else np.zeros(t.size, bool)
    return {"cycle_variation": variation, "cycle_error": error, "error_ratio": error / max(variation, 1e-12),
            "rhythm_rmse": float(np.sqrt(np.mean(np.sum((reproduction - demo.Y)[rhythm] ** 2, axis=1)))),
            "start_error": float(np.linalg.norm(reproduction[0] - demo.Y[: max(int(0.1 / demo.dt), 1)].mean(0))),
            "rest_error": float(np.mean(np.linalg.norm((reproduction - demo.Y)[rest], axis=1))) if rest.any()
            else None,
            "peak_acceleration": peak, "recording_peak_acceleration": recorded_peak,
            "acceleration_ratio": peak / max(recorded_peak, 1e-12)}


def constant_columns(Y: np.ndarray) -> list[int]:
    """The indices of the columns of ``Y [L, d]`` that never change (range within :data:`CONSTANT_RANGE`): a
    channel the recorder held still, which the fit encodes in the anchor alone."""
    Y = np.asarray(Y, dtype=np.float64)
    Y = Y[:, None] if Y.ndim == 1 else Y
    limit = CONSTANT_RANGE * np.maximum(np.max(np.abs(Y), axis=0), 1.0)
    return [int(k) for k in np.flatnonzero(np.ptp(Y, axis=0) <= limit)]


def _still_error(t: np.ndarray, reproduction: np.ndarray, start: float, end: float) -> float:
    """The cycle error against a recording that does not move between ``start`` and ``end`` (s, on ``t``): its cycles
    are all its mean, so the error is the RMS of the reproduction's motion about its own mean there."""
    inside = reproduction[(t >= start) & (t <= end)]
    return float(np.sqrt(np.mean(np.sum((inside - inside.mean(axis=0)) ** 2, axis=1))))


def cycle_figures(t: np.ndarray, recorded: np.ndarray, reproduced: np.ndarray, period: float, start: float,
                  end: float) -> tuple[float, float]:
    """``(variation, error)`` (m) of the rhythm ``recorded [L, d]`` (minus its slow part) between ``start`` and
    ``end`` (s, on ``t [L]``) and of ``reproduced [L, d]``: RMS deviation of the recorded cycles from their mean cycle,
    unbiased (times ``sqrt(n / (n - 1))`` for n cycles), and from the reproduction's mean cycle, cut the same way.

    Raises:
        ValueError: fewer than 2 whole cycles.
    """
    recorded_cycles = _cycles(t, recorded, period, start, end)
    reproduced_cycles = _cycles(t, reproduced, period, start, end)
    n_cycles = len(recorded_cycles)
    if n_cycles < 2 or not reproduced_cycles:
        raise ValueError(f"demo: {n_cycles} whole cycle(s) of the recording between {start:.3g} s and "
                         f"{end:.3g} s, need 2 to measure its cycle-to-cycle variation")
    mean_recorded = np.mean(recorded_cycles, axis=0)
    mean_reproduced = _aligned_mean(reproduced_cycles, mean_recorded)
    spread = np.mean([np.sum((c - mean_recorded) ** 2, axis=1) for c in recorded_cycles])
    variation = float(np.sqrt(spread * n_cycles / (n_cycles - 1)))      # unbiased: the mean is of the same cycles
    error = float(np.sqrt(np.mean([np.sum((c - mean_reproduced) ** 2, axis=1) for c in recorded_cycles])))
    return variation, error


def _aligned_mean(cycles: list[np.ndarray], reference: np.ndarray) -> np.ndarray:
    """The mean of ``cycles`` (each ``[P, d]``) shifted in phase onto ``reference [P, d]`` (a cut may fall at
    another phase of the reproduction's cycle than of the recording's)."""
    mean = np.mean(cycles, axis=0)
    shifts = [np.sum((np.roll(mean, k, axis=0) - reference) ** 2) for k in range(mean.shape[0])]
    return np.roll(mean, int(np.argmin(shifts)), axis=0)
