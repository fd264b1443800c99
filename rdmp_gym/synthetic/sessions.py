"""Synthetic recordings with several sessions: a person works, leaves, rests and comes back, in one file.

Each session is a :func:`rdmp_gym.synthetic.demonstrations.realistic_recording` (rest, approach, a rhythm that grows and
fades, departure, rest); the next session starts where the previous one came to rest (its samples moved so that its
noise-free start meets the previous noise-free end) and its clock continues the previous one. The truth of each
session comes beside it (:class:`SessionTruth`), times from the first sample of the whole recording.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..dmp import quaternion
from ..recordings.pose_io import write_pose_csv
from ..validation import check_positive
from .demonstrations import ENTRY_PERIODS, EXIT_PERIODS, RECORDING_KINDS, Recording, realistic_recording
from .pose import PoseRecording, realistic_pose_recording

__all__ = ["MultiSessionPoseRecording", "MultiSessionRecording", "SessionTruth", "multi_session_pose_recording",
           "multi_session_recording"]


@dataclass(frozen=True)
class SessionTruth:
    """What happened in one session (s from the recording's first sample).

    Attributes:
        onset: the pattern starts to grow (the first stroke).
        rhythm_start, rhythm_end: the pattern runs at full size.
        stop: the pattern has faded (the hand leaves the rhythm).
        rest_time: the hand rests from here until the next session's approach.
        period: the mean period of its rhythm.
    """

    onset: float
    rhythm_start: float
    rhythm_end: float
    stop: float
    rest_time: float
    period: float


@dataclass(frozen=True, eq=False)
class MultiSessionRecording:
    """A recording with several sessions: its samples (``recording.t [L]``, ``recording.Y [L, 3]``), the truth of
    each session, and the samples without sensor noise ``clean [L, 3]``."""

    recording: Recording
    sessions: tuple[SessionTruth, ...]
    clean: np.ndarray


@dataclass(frozen=True, eq=False)
class MultiSessionPoseRecording:
    """A pose recording with several sessions: stamps ``t [L]``, positions ``Y [L, 3]``, unit quaternions
    ``Q [L, 4]`` (either sign), the truth of each session and the noise-free orientation
    ``clean_orientation [L, 4]``."""

    t: np.ndarray
    Y: np.ndarray
    Q: np.ndarray
    name: str
    sessions: tuple[SessionTruth, ...]
    clean_orientation: np.ndarray

    def to_csv(self, path: str | Path, time_column: str = "t") -> None:
        """Write the samples as CSV: ``time_column, x, y, z, qw, qx, qy, qz`` (17 significant digits)."""
        write_pose_csv(path, self.t, self.Y, self.Q, time_column)


def multi_session_recording(n_sessions: int = 3, kind: str = "wiping", *, rng: np.random.Generator,
                            periods: Sequence[float] | None = None, rate: float = 100.0,
                            **session_kwargs) -> MultiSessionRecording:
    """``n_sessions`` sessions of ``kind`` (:data:`~rdmp_gym.synthetic.demonstrations.RECORDING_KINDS`) back to back.

    Args:
        n_sessions: how many sessions (at least 2).
        kind: the kind of every session.
        rng: the only source of randomness, drawn session by session.
        periods: each session's mean period (s; default: the kind's, times 0.85, 1.0, 1.15, ... in turn).
        rate: the recorder's mean sampling rate (Hz).
        session_kwargs: passed on to :func:`~rdmp_gym.synthetic.demonstrations.realistic_recording` (``n_periods``,
            ``noise``, ...).
    """
    periods = _periods(n_sessions, kind, periods)
    rate = check_positive(rate, "rate")
    pieces = [realistic_recording(kind, rng=rng, rate=rate, period=check_positive(period, "periods"),
                                  **session_kwargs) for period in periods]
    t, Y, clean, truths = _chained(pieces, rate)
    recording = Recording(t=t, Y=Y, name=f"{n_sessions} {kind} sessions")
    return MultiSessionRecording(recording=recording, sessions=truths, clean=clean)


def multi_session_pose_recording(n_sessions: int = 2, kind: str = "wiping", *, rng: np.random.Generator,
                                 periods: Sequence[float] | None = None, rate: float = 100.0,
                                 **session_kwargs) -> MultiSessionPoseRecording:
    """``n_sessions`` pose sessions of ``kind`` back to back (:func:`multi_session_recording` with
    :func:`~rdmp_gym.synthetic.pose.realistic_pose_recording`'s orientations); each session's orientations turned
    (about the world's axes) so that its noise-free start meets the previous session's noise-free end.

    Args:
        n_sessions, kind, rng, periods, rate: as in :func:`multi_session_recording`.
        session_kwargs: passed on to ``realistic_pose_recording`` (``tilt``, ``noise``, ``n_periods``, ...).
    """
    periods = _periods(n_sessions, kind, periods)
    rate = check_positive(rate, "rate")
    pieces = [realistic_pose_recording(kind, rng=rng, rate=rate, period=check_positive(period, "periods"),
                                       **session_kwargs) for period in periods]
    t, Y, _, truths = _chained(pieces, rate)
    Q, clean = [], []
    for piece in pieces:
        turn = np.array([1.0, 0.0, 0.0, 0.0]) if not clean else \
            quaternion.multiply(clean[-1][-1], quaternion.conjugate(piece.clean_orientation[0]))
        Q.append(quaternion.multiply(turn, piece.Q))
        clean.append(quaternion.multiply(turn, piece.clean_orientation))
    return MultiSessionPoseRecording(t=t, Y=Y, Q=np.concatenate(Q), name=f"{n_sessions} {kind} pose sessions",
                                     sessions=truths, clean_orientation=np.concatenate(clean))


def _periods(n_sessions: int, kind: str, periods: Sequence[float] | None) -> Sequence[float]:
    """Check ``n_sessions`` and ``kind``; each session's period (default: the kind's, times 0.85, 1.0, 1.15, ...)."""
    if isinstance(n_sessions, bool) or not isinstance(n_sessions, (int, np.integer)) or n_sessions < 2:
        raise ValueError(f"n_sessions: expected an int of at least 2, got {n_sessions!r}")
    if kind not in RECORDING_KINDS:
        raise ValueError(f"kind: expected one of {sorted(RECORDING_KINDS)}, got {kind!r}")
    if periods is None:
        periods = [RECORDING_KINDS[kind].period * (0.85, 1.0, 1.15)[k % 3] for k in range(n_sessions)]
    if len(periods) != n_sessions:
        raise ValueError(f"periods: expected {n_sessions} values (one per session), got {len(periods)}")
    return periods


def _chained(pieces: Sequence[Recording | PoseRecording], rate: float
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray, tuple[SessionTruth, ...]]:
    """The sessions' stamps ``[L]``, positions and noise-free positions ``[L, 3]`` back to back (each moved to
    start where the previous one came to rest, its clock continuing the previous one's) and their truths."""
    times, samples, cleans, truths = [], [], [], []
    clock, place = 0.0, None
    for piece in pieces:
        truth = piece.truth
        shift = np.zeros(3) if place is None else place - truth.clean[0]
        times.append(clock + piece.t)
        samples.append(piece.Y + shift)
        cleans.append(truth.clean + shift)
        truths.append(SessionTruth(onset=clock + truth.rhythm_start - ENTRY_PERIODS * truth.period,
                                   rhythm_start=clock + truth.rhythm_start, rhythm_end=clock + truth.rhythm_end,
                                   stop=clock + truth.rhythm_end + EXIT_PERIODS * truth.period,
                                   rest_time=clock + truth.rest_time, period=truth.period))
        clock += float(piece.t[-1]) + 1.0 / rate
        place = cleans[-1][-1]
    return np.concatenate(times), np.concatenate(samples), np.concatenate(cleans), tuple(truths)
