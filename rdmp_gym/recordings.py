"""Realistic recordings of rhythmic manipulation: what a person records when they show a robot how to wipe.

The hand rests, approaches the working point (slowly, with pauses), starts the rhythm, works while the
working point drifts, leaves, and rests again (drifting a little). The rhythm is not a copy of one cycle:
amplitude and period vary by about 10 % from cycle to cycle. The sensor adds coloured noise and, rarely, an
outlier; the clock stamps the samples unevenly and sometimes drops one.

:func:`realistic_recording` draws such a recording (table frame, metres) from a numpy Generator, with the
true change points beside it (:class:`RecordingTruth`); :func:`despike` and :func:`to_demonstration` turn
samples with uneven stamps and outliers into a :class:`~rdmp_gym.demonstrations.Demonstration` on an even grid.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from scipy.interpolate import CubicSpline, PchipInterpolator
from scipy.ndimage import median_filter

from .demonstrations import Demonstration, _smoothstep7
from .validation import as_finite_array, check_positive, check_time_grid

__all__ = ["RECORDING_KINDS", "Recording", "RecordingTruth", "despike", "realistic_recording", "to_demonstration"]


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
_ENTRY_PERIODS = 0.75       # the pattern grows from nothing to its size over this share of a period
_EXIT_PERIODS = 0.5         # ... and fades over this share of a period as the hand leaves
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
    entry_length = _ENTRY_PERIODS * period
    rhythm_start = arrival                        # the pattern grows during the last part of the approach
    entry_begin = rhythm_start - entry_length
    # the phase drives the cycles; the rhythm ends after n_periods cycles counted from the start of its growth
    t_fine = np.arange(0.0, arrival + (n_periods + 6) * period * 1.6 + settings.departure + settings.rest, 0.002)
    phase = _phase(t_fine, entry_begin, period, spread, rng)
    rhythm_end = float(np.interp(2.0 * np.pi * n_periods, phase, t_fine))
    exit_length = _EXIT_PERIODS * period
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


def _sensor_noise(t: np.ndarray, noise: float, rng: np.random.Generator) -> np.ndarray:
    """Noise ``[L, 3]``: AR(1) with a 50 ms correlation time (std ``noise``), white noise of ``noise / 5``, and
    outliers of 1-3 cm on ``_OUTLIER_RATE`` of the samples."""
    if noise == 0.0:
        return np.zeros((t.size, 3))
    decay = np.exp(-np.diff(t, prepend=t[0]) / 0.05)
    shocks = rng.standard_normal((t.size, 3))
    coloured = np.empty((t.size, 3))
    coloured[0] = shocks[0]
    for i in range(1, t.size):
        coloured[i] = decay[i] * coloured[i - 1] + np.sqrt(1.0 - decay[i] ** 2) * shocks[i]
    out = noise * coloured + 0.2 * noise * rng.standard_normal((t.size, 3))
    spikes = np.flatnonzero(rng.random(t.size) < _OUTLIER_RATE)
    directions = rng.standard_normal((spikes.size, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    out[spikes] += rng.uniform(0.01, 0.03, (spikes.size, 1)) * directions
    return out


def despike(Y: np.ndarray, window: int = 7, threshold: float = 6.0) -> np.ndarray:
    """``Y [L, d]`` with outliers replaced by the running median (a Hampel filter).

    A sample is an outlier where it differs from the median of the ``window`` samples around it by more than
    ``threshold`` times the median absolute difference over the whole signal (1.4826 MAD: the noise's standard
    deviation for Gaussian noise; at least 1e-3 of the signal's range), in any dimension.
    """
    Y = as_finite_array(Y, "Y", ndim=2)
    if window < 3 or window % 2 == 0:
        raise ValueError(f"window: expected an odd number >= 3, got {window!r}")
    median = median_filter(Y, size=(window, 1), mode="nearest")
    deviation = np.abs(Y - median)
    scale = 1.4826 * np.median(deviation, axis=0)
    floor = 1e-3 * np.maximum(np.ptp(Y, axis=0), 1e-12)   # a noise-free signal: only jumps of its size
    outlier = deviation > threshold * np.maximum(scale, floor)
    return np.where(outlier, median, Y)


def to_demonstration(t: np.ndarray, Y: np.ndarray, rate: float = 100.0, *, name: str = "",
                     outliers: bool = True) -> Demonstration:
    """Samples ``Y [L, d]`` at uneven stamps ``t [L]`` (s) as a :class:`Demonstration` on an even grid at
    ``rate`` Hz: outliers removed first (:func:`despike`, unless ``outliers=False``), then a cubic spline."""
    t = check_time_grid(t, "t", uniform=False, min_length=4)
    Y = as_finite_array(Y, "Y", ndim=(1, 2))
    Y = Y[:, None] if Y.ndim == 1 else Y
    if Y.shape[0] != t.size:
        raise ValueError(f"Y: expected {t.size} rows (one per time stamp), got shape {Y.shape}")
    return Demonstration.from_samples(t, despike(Y) if outliers else Y, name=name, rate=rate)
