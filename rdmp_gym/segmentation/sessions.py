"""Several sessions in one recording: rhythms separated by departures or rests, each with its own approach.

People record sessions back to back: wipe, lift the hand, reposition, wipe again. Method:

1. Find a rhythm. :func:`~rdmp_gym.segmentation.segment_rhythm` on the part of the recording still searched
   finds its longest full-size rhythm at that part's own period (sessions may differ in tempo). It is a session
   when it repeats (:func:`repetition`: each stretch of it resembles the stretch a period later, at least
   :data:`MIN_REPETITION`; a departure and a return can look rhythmic to the local fits but do not repeat) and is
   at least :data:`MIN_LEVEL` of the largest session's size.
2. Take it out of the search: from where the hand entered it to where it left it (its ``rhythm_onset`` and
   ``rhythm_stop``, :mod:`rdmp_gym.segmentation.onset`) the recording is replaced by a straight line, and the
   search starts again, until no rhythm of ``min_periods`` periods that repeats is left.
3. Rhythms less than half a period apart are one session (a hesitation, not a departure). Cut between
   neighbouring sessions where the hand is stillest: in the middle of the longest rest between them,
   or at the slowest sample where it never rests. Each session is the recording between its cuts (the first from
   the first sample, the last to the last), segmented again on its own, as a whole recording.
"""

from __future__ import annotations

import itertools
import logging
from dataclasses import dataclass

import numpy as np

from rdmp_gym.demonstrations import Demonstration

from .recording import RhythmSegmentation, segment_rhythm
from .rest import motion_speed, rest_threshold

__all__ = ["MIN_LEVEL", "MIN_REPETITION", "Session", "find_sessions", "repetition"]

logger = logging.getLogger(__name__)

MIN_REPETITION = 0.5
"""The least :func:`repetition` of a rhythm that counts as a session."""

MIN_LEVEL = 0.3
"""The least size of a session's rhythm, as a share of the largest session's."""


@dataclass(frozen=True, eq=False)
class Session:
    """One session of a recording (times in s from the recording's first sample).

    Attributes:
        start, stop: the part of the recording that holds it (its cuts).
        rhythm_onset, rhythm_stop: the hand enters its rhythm and leaves it (those of ``segmentation``; the first
            entry and last exit where the session holds rhythms less than half a period apart).
        segmentation: :func:`segment_rhythm` of that part (times from ``start``; its full-size rhythm is the
            session's longest).
    """

    start: float
    stop: float
    rhythm_onset: float
    rhythm_stop: float
    segmentation: RhythmSegmentation

    def part(self, demo: Demonstration) -> Demonstration:
        """The samples of ``demo`` between the cuts (its own times kept)."""
        t = demo.t - demo.t[0]
        inside = (t >= self.start - 0.5 * demo.dt) & (t <= self.stop + 0.5 * demo.dt)
        return Demonstration(demo.t[inside], demo.Y[inside], name=demo.name)


def repetition(demo: Demonstration, seg: RhythmSegmentation) -> float:
    """How well the full-size rhythm of ``seg`` repeats itself a period later (1: exactly; about 0: unrelated):
    ``2 <a, b> / (|a|^2 + |b|^2)`` of ``a = Z(t)`` and ``b = Z(t + period)`` over the rhythm, ``Z`` the motion
    minus its slow part."""
    t = demo.t - demo.t[0]
    lag = round(seg.period / demo.dt)
    first, last = np.searchsorted(t, [seg.rhythm_start, seg.rhythm_end])
    Z = demo.Y - seg.slow
    a, b = Z[first:last + 1 - lag], Z[first + lag:last + 1]
    energy = float(np.sum(a**2) + np.sum(b**2))
    return 2.0 * float(np.sum(a * b)) / energy if energy > 0.0 else 0.0


def find_sessions(demo: Demonstration, *, min_periods: float = 2.0) -> list[Session]:
    """The sessions of a recording, in time order (see the module docstring).

    Args:
        demo: the recording on an even grid, outliers removed (:func:`rdmp_gym.demonstrations.to_demonstration`).
        min_periods: the fewest periods of full-size rhythm a session holds.
    Raises:
        ValueError: no rhythm that repeats anywhere in the recording.
    """
    if not isinstance(demo, Demonstration):
        raise TypeError(f"demo: expected a Demonstration, got {type(demo).__name__}")
    found: list[tuple[int, int, float, float]] = []        # (onset, stop, size, period) in samples of demo
    searched, pending = demo, [(0, 0, demo.n_samples, demo.n_samples)]
    while pending:       # (padded start, start, end, padded end): the part to search and the found sessions around it
        pad_low, low, high, pad_high = pending.pop()
        rhythm = _rhythm_in(searched, pad_low, pad_high, min_periods)
        if rhythm is None or not low <= rhythm[0] < high:
            continue
        found.append(rhythm)
        searched = _without(searched, rhythm[0], rhythm[1])
        pending += [(pad_low, low, rhythm[0], rhythm[1] + 1), (rhythm[0], rhythm[1] + 1, high, pad_high)]
    if not found:
        raise ValueError("demo: no rhythm found that repeats (no session)")
    largest = max(rhythm[2] for rhythm in found)
    kept = _merged(sorted(rhythm for rhythm in found if rhythm[2] >= MIN_LEVEL * largest), demo.dt)
    cuts = [0] + [_cut(demo, previous[:2], following[0]) for previous, following in itertools.pairwise(kept)] \
        + [demo.n_samples - 1]
    t = demo.t - demo.t[0]
    while True:         # a part that cannot be segmented as a whole recording joins its neighbour
        segs = [_segmented(demo, a, b, min_periods) for a, b in itertools.pairwise(cuts)]
        failed = [k for k, seg in enumerate(segs) if seg is None]
        if not failed:
            break
        if len(cuts) == 2:
            raise ValueError("demo: no session that can be segmented as a whole recording")
        del cuts[min(failed[0] + 1, len(cuts) - 2)]
    sessions = []
    for (a, b), seg in zip(itertools.pairwise(cuts), segs, strict=True):
        inside = [rhythm for rhythm in kept if a <= rhythm[0] <= b]
        joined = len(inside) > 1 or inside[0][2]
        bounds = (t[inside[0][0]], t[inside[-1][1]]) if joined else (t[a] + seg.rhythm_onset,
                                                                      t[a] + seg.rhythm_stop)
        sessions.append(Session(float(t[a]), float(t[b]), float(bounds[0]), float(bounds[1]), seg))
    logger.info("find_sessions %r: %d session(s) at %s s", demo.name, len(sessions),
                ", ".join(f"{s.rhythm_onset:.1f}-{s.rhythm_stop:.1f}" for s in sessions))
    return sessions


def _segmented(demo: Demonstration, a: int, b: int, min_periods: float) -> RhythmSegmentation | None:
    """:func:`segment_rhythm` of the samples ``[a, b]`` of ``demo``, or ``None`` where it refuses them."""
    try:
        return segment_rhythm(Demonstration(demo.t[a:b + 1], demo.Y[a:b + 1], name=demo.name),
                              min_periods=min_periods)
    except ValueError:
        return None


def _rhythm_in(demo: Demonstration, low: int, high: int, min_periods: float
               ) -> tuple[int, int, float, float] | None:
    """``(onset, stop, size, period)`` of the longest rhythm that repeats in the samples ``[low, high)`` of
    ``demo`` (indices into ``demo``; size: the median of its amplitude, m; period: s), or ``None``."""
    if (high - low) * demo.dt < 2.0:
        return None
    part = Demonstration(demo.t[low:high], demo.Y[low:high], name=demo.name)
    try:
        seg = segment_rhythm(part, min_periods=min_periods)
    except ValueError:
        return None
    if repetition(part, seg) < MIN_REPETITION:
        return None
    t = part.t - part.t[0]
    first, last = np.searchsorted(t, [seg.rhythm_start, seg.rhythm_end])
    onset, stop = np.searchsorted(t, [seg.rhythm_onset, seg.rhythm_stop])
    return low + int(onset), low + int(stop), float(np.median(seg.amplitude[first:last + 1])), seg.period


def _merged(rhythms: list[tuple[int, int, float, float]], dt: float) -> list[tuple[int, int, bool]]:
    """``(onset, stop, merged)`` of the rhythms in time order, those less than half a period apart (a hesitation,
    not a departure) merged into one."""
    merged = [[*rhythms[0][:2], False]]
    for (_, stop, _, period), (onset, next_stop, _, next_period) in itertools.pairwise(rhythms):
        if (onset - stop) * dt < 0.5 * min(period, next_period):
            merged[-1][1:] = [next_stop, True]
        else:
            merged.append([onset, next_stop, False])
    return [(onset, stop, joined) for onset, stop, joined in merged]


def _without(demo: Demonstration, onset: int, stop: int) -> Demonstration:
    """``demo`` with the samples ``[onset, stop]`` replaced by the straight line between their ends: a session
    found is taken out of the search, and the recording keeps its edges (its rests) for the next."""
    share = np.linspace(0.0, 1.0, stop - onset + 1)[:, None]
    Y = demo.Y.copy()
    Y[onset:stop + 1] = (1.0 - share) * demo.Y[onset] + share * demo.Y[stop]
    return Demonstration(demo.t, Y, name=demo.name)


def _cut(demo: Demonstration, previous: tuple[int, int], before: int) -> int:
    """Where to cut between a session whose rhythm the hand enters and leaves at the samples ``previous`` and the
    next it enters at ``before``: the middle of the longest rest between (a rhythm holds none), else the slowest
    sample after it left the previous rhythm."""
    speed = motion_speed(demo)
    onset, after = previous
    if before <= after + 1:
        return (after + before) // 2
    resting = speed[onset:before + 1] < rest_threshold(speed, demo.dt, float(np.median(speed)), 0.05)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], resting.astype(np.int8), [0]])))
    if edges.size:
        longest = int(np.argmax(edges[1::2] - edges[::2]))
        return onset + (int(edges[2 * longest]) + int(edges[2 * longest + 1]) - 1) // 2
    return after + int(np.argmin(speed[after:before + 1]))
