"""Several sessions in one recording: rhythms separated by departures or rests, each with its own approach.

People record sessions back to back: wipe, lift the hand, reposition, wipe again. Method:

1. Find a rhythm. :func:`~rdmp_gym.signals.segmentation.segment_rhythm` on the part of the recording still searched
   finds its longest full-size rhythm at that part's own period (sessions may differ in tempo). It counts when it
   repeats (:func:`repetition`: each stretch of it resembles the stretch a period later, at least
   :data:`MIN_REPETITION`; a departure and a return can look rhythmic to the local fits but do not repeat) and is
   at least :data:`MIN_LEVEL` of the largest rhythm's size.
2. Take it out of the search: from its first stroke on the working surface to its last (its ``rhythm_onset``
   and ``rhythm_stop``, :mod:`rdmp_gym.signals.segmentation.onset`) the recording is replaced by a straight line, and
   the search starts again before and after it (with the lines of the rhythms found around, or, where that finds
   none, without them), until no rhythm of ``min_periods`` periods that repeats is left.
3. Group the rhythms into sessions. Neighbouring rhythms are one session when they are less than half a period
   apart (a hesitation), or when the hand pauses between them at the working place: their periods differ by at
   most :data:`SAME_PERIOD`, the pause lasts at most :data:`MAX_PAUSE_PERIODS` periods, and the hand stays within
   :data:`STAY_SHARE` of the rhythms' size of the places they sweep. Only a departure (the hand leaves the working
   place) or a long rest separates sessions.
4. Cut between neighbouring sessions where the hand is stillest: in the middle of the longest rest between them,
   or at the slowest sample where it never rests. Each session is the recording between its cuts (the first from
   the first sample, the last to the last), segmented again on its own, as a whole recording; a part that cannot
   be segmented joins its neighbour.
"""

from __future__ import annotations

import itertools
import logging
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from rdmp_gym.signals.demonstrations import Demonstration
from rdmp_gym.signals.filters import longest_run

from .onset import sweep_size
from .recording import RhythmSegmentation, segment_rhythm
from .rest import motion_speed, rest_threshold

__all__ = ["MAX_PAUSE_PERIODS", "MIN_LEVEL", "MIN_REPETITION", "SAME_PERIOD", "STAY_SHARE", "Session", "find_sessions",
           "repetition"]

logger = logging.getLogger(__name__)

MIN_REPETITION = 0.5
"""The least :func:`repetition` of a rhythm that counts as a session."""

MIN_LEVEL = 0.5
"""The least size of a session's rhythm, as a share of the largest rhythm's: sessions repeat one skill at a
similar size; a slow wobble of the approach that repeats is smaller."""

SAME_PERIOD = 0.15
"""Rhythms whose periods differ by at most this share (of the shorter) can be one session: a person's period
wanders by up to about 10 % from cycle to cycle, and each rhythm's period is estimated on its own."""

MAX_PAUSE_PERIODS = 3.0
"""The longest pause (in periods of the slower rhythm) at the working place within one session."""

STAY_SHARE = 1.0
"""During a pause within a session the hand stays within this share of the rhythms' size (the RMS distance of
their samples from their mean) of a place they sweep; a departure leaves it."""


@dataclass(frozen=True, eq=False)
class Session:
    """One session of a recording (times in s from the recording's first sample).

    Attributes:
        start, stop: the part of the recording that holds it (its cuts).
        rhythm_onset, rhythm_stop: the first and last stroke of its rhythm (those of ``segmentation``; the first
            onset and last stop where the session holds rhythms less than half a period apart).
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
        demo: the recording on an even grid, outliers removed
            (:func:`rdmp_gym.signals.demonstrations.to_demonstration`).
        min_periods: the fewest periods of full-size rhythm a session holds.
    Raises:
        ValueError: no rhythm that repeats anywhere in the recording.
    """
    if not isinstance(demo, Demonstration):
        raise TypeError(f"demo: expected a Demonstration, got {type(demo).__name__}")
    found = _search(demo, min_periods)
    if not found:
        raise ValueError("demo: no rhythm found that repeats (no session)")
    largest = max(rhythm.size for rhythm in found)
    groups = _grouped(demo, sorted((rhythm for rhythm in found if rhythm.size >= MIN_LEVEL * largest),
                                   key=lambda rhythm: rhythm.onset))
    cuts = [0] + [_cut(demo, previous, following) for previous, following in itertools.pairwise(groups)] \
        + [demo.n_samples - 1]
    cuts, segs = _segmentable(demo, cuts, min_periods)
    sessions = [_session(demo, a, b, seg, groups) for (a, b), seg in zip(itertools.pairwise(cuts), segs, strict=True)]
    logger.info("find_sessions %r: %d session(s) at %s s", demo.name, len(sessions),
                ", ".join(f"{s.rhythm_onset:.1f}-{s.rhythm_stop:.1f}" for s in sessions))
    return sessions


@dataclass(frozen=True)
class _Rhythm:
    """A rhythm found in the search: its first and last stroke at the samples ``onset`` and ``stop`` (of
    the whole recording); ``size``: the median of its amplitude (m); ``period`` (s)."""

    onset: int
    stop: int
    size: float
    period: float


def _search(demo: Demonstration, min_periods: float) -> list[_Rhythm]:
    """Steps 1 and 2: every rhythm that repeats, the longest first, each taken out of the search once found."""
    found: list[_Rhythm] = []
    searched, pending = demo, [(0, 0, demo.n_samples, demo.n_samples)]
    while pending:       # (padded start, start, end, padded end): the part to search and the found sessions around it
        pad_low, low, high, pad_high = pending.pop()
        rhythm = _rhythm_in(searched, low, high, min_periods)
        if rhythm is None or not low <= rhythm.onset < high:      # the part with its neighbours' lines
            rhythm = _rhythm_in(searched, pad_low, pad_high, min_periods) if (low, high) != (pad_low, pad_high) \
                else None
        if rhythm is None or not low <= rhythm.onset < high:
            continue
        found.append(rhythm)
        searched = _without(searched, rhythm.onset, rhythm.stop)
        pending += [(pad_low, low, rhythm.onset, rhythm.stop + 1), (rhythm.onset, rhythm.stop + 1, high, pad_high)]
    return found


def _rhythm_in(demo: Demonstration, low: int, high: int, min_periods: float) -> _Rhythm | None:
    """The longest rhythm that repeats in the samples ``[low, high)`` of ``demo``, or ``None``."""
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
    return _Rhythm(low + int(onset), low + int(stop), float(np.median(seg.amplitude[first:last + 1])), seg.period)


def _grouped(demo: Demonstration, rhythms: list[_Rhythm]) -> list[list[_Rhythm]]:
    """Step 3: the rhythms (in time order) grouped into sessions."""
    groups = [[rhythms[0]]]
    for rhythm in rhythms[1:]:
        if _one_session(demo, groups[-1], rhythm):
            groups[-1].append(rhythm)
        else:
            groups.append([rhythm])
    return groups


def _one_session(demo: Demonstration, group: list[_Rhythm], rhythm: _Rhythm) -> bool:
    """Whether ``rhythm`` continues the session ``group`` (step 3): a hesitation, or a pause at the working
    place between rhythms of about one period."""
    previous = group[-1]
    stop = max(item.stop for item in group)
    pause = (rhythm.onset - stop) * demo.dt
    shortest, longest = sorted((previous.period, rhythm.period))
    if pause < 0.5 * shortest:
        return True
    if longest > (1.0 + SAME_PERIOD) * shortest or pause > MAX_PAUSE_PERIODS * longest:
        return False
    swept = [demo.Y[item.onset:item.stop + 1] for item in (previous, rhythm)]
    distance = cKDTree(np.concatenate(swept)).query(demo.Y[stop:rhythm.onset + 1])[0]
    return float(np.max(distance)) <= STAY_SHARE * min(sweep_size(points) for points in swept)


def _segmentable(demo: Demonstration, cuts: list[int], min_periods: float
                 ) -> tuple[list[int], list[RhythmSegmentation]]:
    """The ``cuts`` (sample indices, first and last included) without those whose parts cannot be segmented as
    a whole recording (such a part joins its neighbour), and the segmentation of each part."""
    cuts = list(cuts)
    while True:
        segs = [_segmented(demo, a, b, min_periods) for a, b in itertools.pairwise(cuts)]
        failed = [k for k, seg in enumerate(segs) if seg is None]
        if not failed:
            return cuts, segs
        if len(cuts) == 2:
            raise ValueError("demo: no session that can be segmented as a whole recording")
        del cuts[min(failed[0] + 1, len(cuts) - 2)]


def _segmented(demo: Demonstration, a: int, b: int, min_periods: float) -> RhythmSegmentation | None:
    """:func:`segment_rhythm` of the samples ``[a, b]`` of ``demo``, or ``None`` where it refuses them."""
    try:
        return segment_rhythm(Demonstration(demo.t[a:b + 1], demo.Y[a:b + 1], name=demo.name),
                              min_periods=min_periods)
    except ValueError:
        return None


def _session(demo: Demonstration, a: int, b: int, seg: RhythmSegmentation, groups: list[list[_Rhythm]]
             ) -> Session:
    """The session of the samples ``[a, b]``: its rhythm's first and last stroke are its segmentation's,
    or the first onset and last stop of its rhythms where it holds several."""
    t = demo.t - demo.t[0]
    inside = [rhythm for group in groups if a <= group[0].onset <= b for rhythm in group]
    if len(inside) > 1:
        onset, stop = t[inside[0].onset], t[max(rhythm.stop for rhythm in inside)]
    else:
        onset, stop = t[a] + seg.rhythm_onset, t[a] + seg.rhythm_stop
    return Session(float(t[a]), float(t[b]), float(onset), float(stop), seg)


def _without(demo: Demonstration, onset: int, stop: int) -> Demonstration:
    """``demo`` with the samples ``[onset, stop]`` replaced by the straight line between their ends: a session
    found is taken out of the search, and the recording keeps its edges (its rests) for the next."""
    share = np.linspace(0.0, 1.0, stop - onset + 1)[:, None]
    Y = demo.Y.copy()
    Y[onset:stop + 1] = (1.0 - share) * demo.Y[onset] + share * demo.Y[stop]
    return Demonstration(demo.t, Y, name=demo.name)


def _cut(demo: Demonstration, previous: list[_Rhythm], following: list[_Rhythm]) -> int:
    """Where to cut between the sessions ``previous`` and ``following`` (their rhythms): the middle of the longest
    rest between the previous onset and the following one (a rhythm holds none), else the slowest sample after the
    hand left the previous session's rhythms."""
    speed = motion_speed(demo)
    onset, after, before = previous[0].onset, max(rhythm.stop for rhythm in previous), following[0].onset
    if before <= after + 1:
        return (after + before) // 2
    resting = speed[onset:before + 1] < rest_threshold(speed, demo.dt, float(np.median(speed)), 0.05)
    first, stop = longest_run(resting)
    if stop > first:
        return onset + (first + stop - 1) // 2
    return after + int(np.argmin(speed[after:before + 1]))
