"""Strikes from the membrane's force at every physics step, and how they fit the beats.

A strike is a run of physics steps in which the tip presses on the membrane with more than ``STRIKE_FORCE``
newtons; runs closer than ``MERGE_GAP`` seconds are one strike (contact chatter). Its onset is the run's first
step, its impulse the force integrated over the run (N s).

Each beat owns the window from half the interval before it to half the interval after it; a strike belongs to the
window its onset falls in. A beat is **struck** when exactly one strike falls in its window, its onset within
``tolerance`` of the beat and its impulse within the band; a window with two strikes is a double bounce, and a
strike outside every window (before the first beat's window, after the last's) is an extra strike.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["MERGE_GAP", "STRIKE_FORCE", "BeatScore", "Strikes", "score_beats"]

#: force (N) above which the tip is striking, and the gap (s) below which two runs are one strike
STRIKE_FORCE = 0.5
MERGE_GAP = 0.01


@dataclass(frozen=True)
class Strikes:
    """The strikes of an episode: onsets ``[S]`` (s), impulses ``[S]`` (N s), peak forces ``[S]`` (N), and their
    first physics steps ``[S]``."""

    onsets: np.ndarray
    impulses: np.ndarray
    peaks: np.ndarray
    first: np.ndarray

    @classmethod
    def from_force(cls, force: np.ndarray, dt: float) -> Strikes:
        """The strikes in a force trace ``[N]`` sampled every ``dt`` seconds (the first sample at ``dt``)."""
        on = np.r_[False, force > STRIKE_FORCE, False]
        edges = np.flatnonzero(np.diff(on.astype(np.int8)))
        starts, ends = list(edges[0::2]), list(edges[1::2])
        gap = max(1, round(MERGE_GAP / dt))
        merged: list[tuple[int, int]] = []
        for start, end in zip(starts, ends, strict=True):
            if merged and start - merged[-1][1] < gap:
                merged[-1] = (merged[-1][0], end)
            else:
                merged.append((start, end))
        first = np.array([s for s, _ in merged], dtype=int)
        impulses = np.array([float(np.sum(force[s:e])) * dt for s, e in merged])
        peaks = np.array([float(np.max(force[s:e])) for s, e in merged])
        return cls((first + 1) * dt, impulses, peaks, first)


@dataclass(frozen=True)
class BeatScore:
    """How the strikes fit the beats ``[B]``.

    Attributes:
        count: strikes in each beat's window ``[B]``.
        error: onset minus beat of the window's first strike ``[B]`` (s; NaN where none).
        impulse: impulse of the window's first strike ``[B]`` (N s; NaN where none).
        struck: the beat is struck (see the module docstring) ``[B]``.
        extra: strikes outside every window.
        strike_beat: the beat each strike belongs to ``[S]`` (-1 outside every window).
    """

    count: np.ndarray
    error: np.ndarray
    impulse: np.ndarray
    struck: np.ndarray
    extra: int
    strike_beat: np.ndarray


def score_beats(strikes: Strikes, beats: np.ndarray, tolerance: float, band: tuple[float, float]) -> BeatScore:
    """Fit ``strikes`` to the beat times ``beats [B]`` (s, increasing, B >= 2) with a timing ``tolerance`` (s) and an
    impulse ``band`` (N s)."""
    gaps = np.diff(beats)
    half_before = 0.5 * np.r_[gaps[:1], gaps]
    half_after = 0.5 * np.r_[gaps, gaps[-1:]]
    low, high = beats - half_before, beats + half_after
    owner = np.full(len(strikes.onsets), -1)
    for index, onset in enumerate(strikes.onsets):
        inside = np.flatnonzero((onset >= low) & (onset < high))
        if inside.size:
            owner[index] = int(inside[0])
    count = np.bincount(owner[owner >= 0], minlength=len(beats))
    error = np.full(len(beats), np.nan)
    impulse = np.full(len(beats), np.nan)
    for beat in range(len(beats)):
        mine = np.flatnonzero(owner == beat)
        if mine.size:
            error[beat] = strikes.onsets[mine[0]] - beats[beat]
            impulse[beat] = strikes.impulses[mine[0]]
    with np.errstate(invalid="ignore"):
        struck = (count == 1) & (np.abs(error) <= tolerance) & (impulse >= band[0]) & (impulse <= band[1])
    return BeatScore(count, error, impulse, struck, int(np.sum(owner < 0)), owner)
