"""Synthetic data: demonstrations and recordings drawn with known truth, for tests, benchmarks and examples.

* Composed-periodic wiping demonstrations in the four styles of Ernesti et al. 2012, Fig. 7
  (:func:`wiping_demonstration`), several sharing one pattern with their own starts
  (:func:`multi_transient_demonstrations`), and one that ends at a goal (:func:`ending_demonstration`). They live
  in a table frame (metres): x, y in the table plane, z the height above the table surface. A demonstration
  starts at rest at ``start`` and blends into a periodic pattern around ``anchor`` with a 7th-order smoothstep,
  so it is C^3 at the transient length ``T`` and exactly periodic (z = anchor z) from ``T`` on; ``truth``
  (:class:`~rdmp_gym.signals.demonstrations.SyntheticTruth`) holds the clean signal and the true values.
* Realistic recordings of a person's rhythmic manipulation (:func:`realistic_recording`): the hand rests,
  approaches the working point (slowly, with pauses), starts the rhythm, works while the working point drifts,
  leaves, and rests again (drifting a little). The rhythm is not a copy of one cycle: amplitude and period vary
  by about 10 % from cycle to cycle. The sensor adds coloured noise and, rarely, an outlier; the clock stamps the
  samples unevenly and sometimes drops one. The true change points come beside it (:class:`RecordingTruth`);
  :func:`rdmp_gym.signals.demonstrations.to_demonstration` puts such samples on an even grid.

Every generator draws from the numpy Generator (or seed) it is given, in a fixed order: the same seed gives the
same samples, bit for bit.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from scipy.interpolate import CubicSpline, PchipInterpolator

from ..signals.demonstrations import Demonstration, SyntheticTruth
from ..validation import as_finite_array, check_positive

__all__ = ["ENTRY_PERIODS", "EXIT_PERIODS", "RECORDING_KINDS", "Recording", "RecordingTruth", "coloured_noise",
           "ending_demonstration", "multi_transient_demonstrations", "realistic_recording", "wiping_demonstration"]

# ---------------------------------------------------------------------------------- wiping demonstrations
_DEFAULT_START = (-0.15, 0.20, 0.12)
_CIRCLE_RADIUS = 0.05
_EIGHT_HALF_SIZE = (0.06, 0.03)  # figure-eight of 0.12 m x 0.06 m
_LOOP = (0.10, -0.08, 0.08)  # complex approach: x loop, sideways swing and lift (m)
# style: (pattern, complex approach, period s, transient length s)
_STYLES = {
    1: ("circle", False, 1.50, 2.0),
    2: ("circle", True, 1.45, 2.5),
    3: ("eight", False, 1.60, 2.0),
    4: ("eight", True, 1.55, 2.5),
}


def _as_generator(rng: np.random.Generator | int | None) -> np.random.Generator:
    if isinstance(rng, np.random.Generator):
        return rng
    if rng is None or (isinstance(rng, (int, np.integer)) and not isinstance(rng, bool)):
        return np.random.default_rng(rng)
    raise TypeError(f"rng: expected a numpy.random.Generator, an int seed or None, "
                    f"got {type(rng).__name__}")


def _check_style(style: int) -> tuple[str, bool, float, float]:
    if isinstance(style, bool) or not isinstance(style, (int, np.integer)) or style not in _STYLES:
        raise ValueError(f"style: expected 1, 2, 3 or 4, got {style!r}")
    return _STYLES[int(style)]


def _smoothstep7(u: np.ndarray) -> np.ndarray:
    """7th-order smoothstep: 0 at u <= 0, 1 at u >= 1, derivatives 1..3 zero at both ends."""
    u = np.clip(u, 0.0, 1.0)
    return u**4 * (35.0 - 84.0 * u + 70.0 * u**2 - 20.0 * u**3)


def _pattern(kind: str, tau: np.ndarray, period: float) -> np.ndarray:
    """Zero-mean periodic pattern ``[n, 3]`` at pattern times ``tau`` ``[n]``."""
    angle = 2.0 * np.pi * tau / period
    if kind == "circle":
        xy = _CIRCLE_RADIUS * np.column_stack([np.cos(angle), np.sin(angle)])
    else:
        xy = np.column_stack([_EIGHT_HALF_SIZE[0] * np.sin(angle),
                              _EIGHT_HALF_SIZE[1] * np.sin(2.0 * angle)])
    return np.column_stack([xy, np.zeros_like(angle)])


def _composed(t_rel: np.ndarray, *, kind: str, complex_approach: bool, start: np.ndarray,
              anchor: np.ndarray, period: float, transient_length: float,
              entrance_time: float) -> np.ndarray:
    """Noiseless composed-periodic signal ``[L, 3]`` at times ``t_rel`` ``[L]`` (from the start)."""
    periodic = anchor + _pattern(kind, entrance_time + t_rel - transient_length, period)
    u = t_rel / transient_length
    blend = start + _smoothstep7(u)[:, None] * (periodic - start)
    if complex_approach:
        v = np.clip(u, 0.0, 1.0)
        window = 256.0 * (v * (1.0 - v)) ** 4  # 1 at u = 1/2, derivatives 0..3 zero at both ends
        loop = np.column_stack([np.sin(2.0 * np.pi * v), np.sin(np.pi * v), np.sin(np.pi * v)])
        blend = blend + window[:, None] * loop * np.asarray(_LOOP)
    return np.where((u >= 1.0)[:, None], periodic, blend)


def _vector3(value: object, default: Sequence[float], name: str) -> np.ndarray:
    array = as_finite_array(default if value is None else value, name, ndim=1)
    if array.shape != (3,):
        raise ValueError(f"{name}: expected 3 values (x, y, z), got shape {array.shape}")
    return array


def _time_grid(duration: float, rate: float) -> np.ndarray:
    duration = check_positive(duration, "duration")
    rate = check_positive(rate, "rate")
    n_samples = int(np.floor(duration * rate + 1e-9)) + 1
    if n_samples < 2:
        raise ValueError(f"duration: {duration} s at rate {rate} Hz gives fewer than 2 samples")
    return np.arange(n_samples, dtype=np.float64) / rate


def _check_noise(noise: float) -> float:
    value = float(as_finite_array(noise, "noise", ndim=0))
    if value < 0.0:
        raise ValueError(f"noise: expected a standard deviation >= 0, got {noise!r}")
    return value


def _synthesize(t: np.ndarray, generator: np.random.Generator, noise: float, *, kind: str,
                complex_approach: bool, start: np.ndarray, anchor: np.ndarray, period: float,
                transient_length: float, entrance_time: float, name: str) -> Demonstration:
    entrance = float(np.mod(entrance_time, period))
    if entrance >= period:  # np.mod can round up to period itself
        entrance = 0.0
    clean = _composed(t, kind=kind, complex_approach=complex_approach, start=start, anchor=anchor,
                      period=period, transient_length=transient_length, entrance_time=entrance)
    noisy = clean + noise * generator.standard_normal(clean.shape)
    truth = SyntheticTruth(period=period, transient_length=transient_length, anchor=anchor,
                           clean=clean, entrance_time=entrance)
    return Demonstration(t=t, Y=noisy, name=name, truth=truth)


def wiping_demonstration(style: int = 1, *, rng: np.random.Generator | int | None = 0,
                         duration: float = 10.0, rate: float = 100.0, noise: float = 3e-4,
                         start: Sequence[float] | np.ndarray | None = None,
                         anchor: Sequence[float] | np.ndarray | None = None,
                         period: float | None = None, transient_length: float | None = None,
                         entrance_time: float = 0.0) -> Demonstration:
    """A synthetic wiping demonstration ``Y[L, 3]`` (table frame, m) in one of the paper's styles.

    Styles: 1 simple approach + circle, 2 complex approach + circle, 3 simple approach +
    figure-eight, 4 complex approach + figure-eight. The motion starts at rest at ``start``
    (default (-0.15, 0.20, 0.12)), is exactly periodic around ``anchor`` (default the origin) with
    z = anchor z from ``transient_length`` on (style default 2 s simple, 2.5 s complex), with period
    ``period`` (style default about 1.5 s), entering the pattern at pattern time ``entrance_time``.
    Sampled at ``rate`` Hz over ``[0, duration]``, plus white Gaussian noise of std ``noise`` (m)
    drawn from ``rng`` (a Generator or a seed). ``truth`` holds the clean signal and true values.
    """
    kind, complex_approach, default_period, default_transient = _check_style(style)
    t = _time_grid(duration, rate)
    period = check_positive(default_period if period is None else period, "period")
    transient = check_positive(default_transient if transient_length is None else transient_length,
                               "transient_length")
    if transient >= t[-1]:
        raise ValueError(f"duration: {duration} s must exceed transient_length = {transient} s")
    entrance = float(as_finite_array(entrance_time, "entrance_time", ndim=0))
    return _synthesize(t, _as_generator(rng), _check_noise(noise), kind=kind,
                       complex_approach=complex_approach,
                       start=_vector3(start, _DEFAULT_START, "start"),
                       anchor=_vector3(anchor, (0.0, 0.0, 0.0), "anchor"), period=period,
                       transient_length=transient, entrance_time=entrance,
                       name=f"wiping style {int(style)}")


def _per_demo(value: object, default: np.ndarray, n: int, name: str) -> np.ndarray:
    array = as_finite_array(default if value is None else value, name, ndim=1)
    if array.size != n:
        raise ValueError(f"{name}: expected {n} values (one per demonstration), got {array.size}")
    return array


def multi_transient_demonstrations(n: int = 3, *, rng: np.random.Generator | int | None = 0,
                                   style: int = 1, duration: float = 10.0, rate: float = 100.0,
                                   noise: float = 3e-4, period: float | None = None,
                                   anchor: Sequence[float] | np.ndarray | None = None,
                                   starts: Sequence[Sequence[float]] | np.ndarray | None = None,
                                   transient_lengths: Sequence[float] | np.ndarray | None = None,
                                   entrance_times: Sequence[float] | np.ndarray | None = None,
                                   ) -> list[Demonstration]:
    """``n`` synthetic demonstrations ``Y[L, 3]`` sharing ONE periodic pattern (that of ``style``).

    Each has its own start (``starts`` ``[n, 3]``, default on an arc 0.25 m from the anchor, 0.12 m
    up), transient length (``transient_lengths`` ``[n]``, default evenly from 1.5 s to 2.6 s) and
    entrance time into the pattern (``entrance_times`` ``[n]``, default ``k * period / n``). Noise
    is drawn from the one generator ``rng`` in demonstration order. Other arguments as in
    :func:`wiping_demonstration`.
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ValueError(f"n: expected a positive int, got {n!r}")
    kind, complex_approach, default_period, _ = _check_style(style)
    t = _time_grid(duration, rate)
    period = check_positive(default_period if period is None else period, "period")
    index = np.arange(n)
    lengths = _per_demo(transient_lengths, 1.5 + 1.1 * index / max(n - 1, 1), n,
                        "transient_lengths")
    if np.any(lengths <= 0.0) or np.any(lengths >= t[-1]):
        raise ValueError(f"transient_lengths: expected values in (0, duration={t[-1]}), "
                         f"got {lengths}")
    entrances = _per_demo(entrance_times, index * period / n, n, "entrance_times")
    anchor_vector = _vector3(anchor, (0.0, 0.0, 0.0), "anchor")
    angles = 0.75 * np.pi + 2.0 * np.pi * index / n
    default_starts = anchor_vector + np.column_stack([0.25 * np.cos(angles), 0.25 * np.sin(angles),
                                                      np.full(n, 0.12)])
    start_array = as_finite_array(default_starts if starts is None else starts, "starts", ndim=2)
    if start_array.shape != (n, 3):
        raise ValueError(f"starts: expected shape ({n}, 3), got {start_array.shape}")
    generator = _as_generator(rng)
    noise = _check_noise(noise)
    return [_synthesize(t, generator, noise, kind=kind, complex_approach=complex_approach,
                        start=start_array[k], anchor=anchor_vector, period=period,
                        transient_length=float(lengths[k]), entrance_time=float(entrances[k]),
                        name=f"wiping style {int(style)}, transient {k + 1} of {n}")
            for k in range(n)]


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


# ---------------------------------------------------------------------------------- realistic recordings
@dataclass(frozen=True)
class _Kind:
    """Settings of one kind of recording (times in s, lengths in m)."""

    approach: tuple[float, ...]     # durations of the approach's moves; a pause between consecutive ones
    pause: float                    # length of each pause
    period: float
    n_periods: int
    radii: tuple[float, float]      # half-axes of the elliptic pattern in the table plane
    drift: float                    # how far the working point wanders during the rhythm
    departure: float
    rest: float


#: the kinds of recording :func:`realistic_recording` draws
RECORDING_KINDS = {
    "wiping": _Kind(approach=(3.0,), pause=0.0, period=1.7, n_periods=4, radii=(0.05, 0.05), drift=0.015,
                    departure=1.8, rest=2.0),
    "kitchen": _Kind(approach=(3.5, 1.5), pause=1.5, period=0.9, n_periods=20, radii=(0.06, 0.025), drift=0.03,
                     departure=2.0, rest=2.5),
    "long": _Kind(approach=(4.0, 3.0, 2.5), pause=1.2, period=1.3, n_periods=8, radii=(0.05, 0.04), drift=0.02,
                  departure=2.5, rest=2.5),
}
_INITIAL_REST = 0.8         # s at rest before the hand moves
ENTRY_PERIODS = 0.75
"""In a :func:`realistic_recording` the pattern grows from nothing to its size over this share of a period, ending
at ``truth.rhythm_start``."""
EXIT_PERIODS = 0.5
"""... and fades over this share of a period from ``truth.rhythm_end`` as the hand leaves."""
_OUTLIER_RATE = 0.002       # share of samples that are outliers


@dataclass(frozen=True, eq=False)
class RecordingTruth:
    """What happened in a :func:`realistic_recording` (times from the first sample, s).

    Attributes:
        onset: the hand leaves its first rest.
        rhythm_start: the pattern runs at full size from here (its growth ends).
        rhythm_end: the pattern starts to fade as the hand leaves.
        rest_time: the hand is at rest (apart from a slow drift) from here.
        period: the mean period of the rhythm.
        cycle_variation: the relative spread of amplitude and period from cycle to cycle.
        working_point: ``[L, d]`` the centre of the pattern (the slow part of the motion) at each sample.
        clean: ``[L, d]`` the samples without sensor noise.
    """

    onset: float
    rhythm_start: float
    rhythm_end: float
    rest_time: float
    period: float
    cycle_variation: float
    working_point: np.ndarray
    clean: np.ndarray


@dataclass(frozen=True, eq=False)
class Recording:
    """Samples ``Y [L, d]`` at uneven time stamps ``t [L]`` (s), as a recorder writes them."""

    t: np.ndarray
    Y: np.ndarray
    name: str = ""
    truth: RecordingTruth | None = None

    def to_csv(self, path: str | Path, time_column: str = "t") -> None:
        """Write the samples as CSV: ``time_column``, then x, y, z (17 significant digits)."""
        header = ",".join([time_column, *["x", "y", "z"][: self.Y.shape[1]]])
        np.savetxt(path, np.column_stack([self.t, self.Y]), fmt="%.17g", delimiter=",", header=header,
                   comments="")


def _smooth_profile(knots_t: np.ndarray, values: np.ndarray, t: np.ndarray) -> np.ndarray:
    """A smooth curve through ``values [K]`` at ``knots_t [K]`` (a cubic spline, constant outside), at ``t``."""
    return CubicSpline(knots_t, values, bc_type="clamped")(np.clip(t, knots_t[0], knots_t[-1]))


def _phase(t: np.ndarray, start: float, period: float, spread: float, rng: np.random.Generator) -> np.ndarray:
    """Pattern phase (rad) at ``t [L]`` (increasing): 0 at ``start``; each cycle's period drawn within
    ``period (1 +- spread)``; cycles before ``start`` have the mean period."""
    n_cycles = int(np.ceil((t[-1] - start) / (period * (1.0 - spread)))) + 2
    periods = period * (1.0 + spread * rng.uniform(-1.0, 1.0, n_cycles))
    ends = start + np.concatenate([[0.0], np.cumsum(periods)])
    # the phase passes k * 2 pi at the end of cycle k; a monotone cubic between: no kink at the cycle ends
    lead = int(np.ceil((start - t[0]) / period)) + 1
    knots = np.concatenate([start - period * np.arange(lead, 0, -1), ends])
    phases = 2.0 * np.pi * np.arange(-lead, ends.size)
    return PchipInterpolator(knots, phases)(t)


def _approach(t: np.ndarray, start: np.ndarray, target: np.ndarray, onset: float, moves: tuple[float, ...],
              pause: float, rng: np.random.Generator) -> tuple[np.ndarray, float]:
    """Positions ``[L, d]`` of a minimum-jerk approach from ``start`` to ``target`` in ``len(moves)`` moves (via
    points scattered about the straight line), with a pause between moves; and the time it arrives."""
    n = len(moves)
    shares = np.sort(rng.uniform(0.3, 0.8, n - 1)) if n > 1 else np.zeros(0)
    via = [start] + [start + s * (target - start) + rng.normal(0.0, 0.03, start.size) * [1, 1, 0.5]
                     for s in shares] + [target]
    path = np.repeat(start[None], t.size, axis=0)
    clock = onset
    for k, duration in enumerate(moves):
        share = _smoothstep7((t - clock) / duration)[:, None]
        path = path + share * (via[k + 1] - via[k])
        clock += duration + (pause if k < n - 1 else 0.0)
    return path, clock


def realistic_recording(kind: str = "wiping", *, rng: np.random.Generator, rate: float = 100.0,
                        cycle_variation: float = 0.1, noise: float = 4e-4, clock_jitter: float = 0.15,
                        n_periods: int | None = None, period: float | None = None,
                        approach: tuple[float, ...] | None = None) -> Recording:
    """A recording ``Y [L, 3]`` (table frame, m) of a person's rhythmic demonstration, at uneven stamps.

    Args:
        kind: ``"wiping"`` (a 3 s approach, a few circles of 1.7 s), ``"kitchen"`` (a 6.5 s approach with a
            pause, about 20 strokes of 0.9 s) or ``"long"`` (an 11 s approach with two pauses); see
            :data:`RECORDING_KINDS`.
        rng: the only source of randomness: start, working point, drift, cycles, noise and clock.
        rate: the recorder's mean sampling rate (Hz).
        cycle_variation: relative spread of each cycle's amplitude and period (uniform in ``+-``).
        noise: standard deviation (m) of the sensor noise: coloured (correlation time 50 ms) plus a white
            fifth; ``_OUTLIER_RATE`` of the samples are outliers of 1-3 cm.
        clock_jitter: relative spread of the sampling intervals; 1 % of the samples are dropped.
        n_periods, period: override the kind's number of periods and mean period (s).
        approach: override the durations (s) of the approach's moves (a pause between consecutive ones).

    One function of more than 80 lines on purpose: its draws from ``rng`` come in one fixed order that the
    benchmarked recordings depend on, and most of its length is the checks of the arguments.
    """
    if kind not in RECORDING_KINDS:
        raise ValueError(f"kind: expected one of {sorted(RECORDING_KINDS)}, got {kind!r}")
    if not isinstance(rng, np.random.Generator):
        raise TypeError(f"rng: expected a numpy.random.Generator, got {type(rng).__name__}")
    settings = RECORDING_KINDS[kind]
    if approach is not None:
        moves = tuple(float(check_positive(move, "approach")) for move in np.atleast_1d(approach))
        settings = replace(settings, approach=moves)
    rate = check_positive(rate, "rate")
    period = check_positive(settings.period if period is None else period, "period")
    n_periods = settings.n_periods if n_periods is None else int(n_periods)
    if n_periods < 2:
        raise ValueError(f"n_periods: expected at least 2, got {n_periods!r}")
    spread = float(as_finite_array(cycle_variation, "cycle_variation", ndim=0))
    if not 0.0 <= spread < 0.5:
        raise ValueError(f"cycle_variation: expected a value in [0, 0.5), got {cycle_variation!r}")
    if not float(as_finite_array(noise, "noise", ndim=0)) >= 0.0:
        raise ValueError(f"noise: expected a standard deviation >= 0, got {noise!r}")
    if not 0.0 <= clock_jitter < 0.5:
        raise ValueError(f"clock_jitter: expected a value in [0, 0.5), got {clock_jitter!r}")

    onset = _INITIAL_REST * rng.uniform(0.8, 1.2)
    start = np.array([rng.uniform(-0.25, -0.15), rng.uniform(0.1, 0.25), rng.uniform(0.12, 0.2)])
    working = np.array([rng.uniform(-0.05, 0.05), rng.uniform(-0.05, 0.05), 0.0])
    goal = working + np.array([rng.uniform(0.1, 0.2), rng.uniform(-0.2, -0.1), rng.uniform(0.1, 0.16)])
    arrival = onset + sum(settings.approach) + settings.pause * (len(settings.approach) - 1)
    entry_length = ENTRY_PERIODS * period
    rhythm_start = arrival                        # the pattern grows during the last part of the approach
    entry_begin = rhythm_start - entry_length
    # the phase drives the cycles; the rhythm ends after n_periods cycles counted from the start of its growth
    t_fine = np.arange(0.0, arrival + (n_periods + 6) * period * 1.6 + settings.departure + settings.rest, 0.002)
    phase = _phase(t_fine, entry_begin, period, spread, rng)
    rhythm_end = float(np.interp(2.0 * np.pi * n_periods, phase, t_fine))
    exit_length = EXIT_PERIODS * period
    depart_end = rhythm_end + settings.departure
    rest_time = depart_end
    duration = rest_time + settings.rest * rng.uniform(0.9, 1.2)

    t = _uneven_clock(duration, rate, clock_jitter, rng)
    phase = np.interp(t, t_fine, phase)
    approach, _ = _approach(t, start, working, onset, settings.approach, settings.pause, rng)
    wander = working + settings.drift * rng.uniform(-1.0, 1.0, 3) * [1.0, 1.0, 0.1]
    drift_share = _smoothstep7((t - rhythm_start) / (rhythm_end - rhythm_start))[:, None]
    during = approach + drift_share * (wander - working)
    rest_drift = rng.normal(0.0, 0.002, 3)          # 2 mm over the final rest
    leaving = _smoothstep7((t - rhythm_end) / settings.departure)[:, None]
    settle = np.clip((t - rest_time) / settings.rest, 0.0, None)[:, None]
    working_point = during + leaving * (goal - wander) + settle * rest_drift

    cycles = np.arange(n_periods + 8)
    amplitude = _smooth_profile(entry_begin + cycles * period, 1.0 + spread * rng.uniform(-1.0, 1.0, cycles.size),
                                t)
    envelope = (_smoothstep7((t - entry_begin) / entry_length)
                * (1.0 - _smoothstep7((t - rhythm_end) / exit_length))) * amplitude
    radii = np.array(settings.radii)
    pattern = np.column_stack([radii[0] * np.cos(phase), radii[1] * np.sin(phase),
                               0.004 * np.sin(2.0 * phase)])       # a slight press and release
    clean = working_point + envelope[:, None] * pattern
    Y = clean + _sensor_noise(t, noise, rng)
    truth = RecordingTruth(onset=float(onset), rhythm_start=float(rhythm_start), rhythm_end=float(rhythm_end),
                           rest_time=float(rest_time), period=period, cycle_variation=spread,
                           working_point=working_point, clean=clean)
    return Recording(t=t, Y=Y, name=f"{kind} recording", truth=truth)


def _uneven_clock(duration: float, rate: float, jitter: float, rng: np.random.Generator) -> np.ndarray:
    """Time stamps ``[L]`` from 0 to about ``duration``: intervals ``(1 + jitter N(0, 1)) / rate`` (at least a
    fifth of the nominal one), 1 % of the samples dropped."""
    n = int(duration * rate * 1.02) + 2
    steps = np.maximum(1.0 + jitter * rng.standard_normal(n), 0.2) / rate
    t = np.concatenate([[0.0], np.cumsum(steps)])
    t = t[t <= duration]
    keep = rng.random(t.size) >= 0.01
    keep[[0, -1]] = True
    return t[keep]


def coloured_noise(t: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Unit-variance AR(1) noise ``[L, 3]`` at the (possibly uneven) times ``t [L]``, correlation time 50 ms."""
    decay = np.exp(-np.diff(t, prepend=t[0]) / 0.05)
    shocks = rng.standard_normal((t.size, 3))
    coloured = np.empty((t.size, 3))
    coloured[0] = shocks[0]
    for i in range(1, t.size):
        coloured[i] = decay[i] * coloured[i - 1] + np.sqrt(1.0 - decay[i] ** 2) * shocks[i]
    return coloured


def _sensor_noise(t: np.ndarray, noise: float, rng: np.random.Generator) -> np.ndarray:
    """Noise ``[L, 3]``: AR(1) with a 50 ms correlation time (std ``noise``), white noise of ``noise / 5``, and
    outliers of 1-3 cm on ``_OUTLIER_RATE`` of the samples."""
    if noise == 0.0:
        return np.zeros((t.size, 3))
    out = noise * coloured_noise(t, rng) + 0.2 * noise * rng.standard_normal((t.size, 3))
    spikes = np.flatnonzero(rng.random(t.size) < _OUTLIER_RATE)
    directions = rng.standard_normal((spikes.size, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    out[spikes] += rng.uniform(0.01, 0.03, (spikes.size, 1)) * directions
    return out
