"""Fit the sessions of a recording with several: one DMP per session, or one DMP for all of them.

:func:`rdmp_gym.signals.segmentation.sessions.find_sessions` cuts the recording between its sessions.
:func:`fit_sessions` fits each part as a whole recording of its own (rest or motion, approach, rhythm, departure, rest)
with :func:`rdmp_gym.recordings.recording_fit.fit_recording` (:func:`fit_pose_sessions`: each part of a pose recording
with :func:`rdmp_gym.recordings.pose_fit.fit_pose_recording`). :func:`fit_joint` fits one rhythm to all of them: each
session's rhythm relative to its own working point (its anchor), with its cycles stretched to their mean period and the
session stretched to the sessions' common period, is one demonstration of :meth:`RhythmicDMP.fit
<rdmp_gym.dmp.rhythmic.RhythmicDMP.fit>`; they share the periodic pattern, and each keeps its entry (a transient) and
its anchor (paper III-E).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..dmp.fitting import FADE_BEFORE_T
from ..dmp.pose import PoseDemonstration
from ..dmp.rhythmic import RhythmicDMP
from ..signals.demonstrations import Demonstration
from ..signals.segmentation import Segmentation, local_fit, segment_rhythm
from ..signals.segmentation.sessions import SAME_PERIOD, Session, find_sessions
from .pose_fit import PoseFit, fit_pose_recording, pose_report
from .recording_fit import (
    ENTRY_PERIODS,
    SMOOTHNESS,
    RecordingFit,
    cycle_figures,
    fit_recording,
    normalise_tempo,
    recording_report,
)

__all__ = ["JointFit", "SessionFit", "fit_joint", "fit_pose_sessions", "fit_sessions", "joint_report"]


@dataclass(frozen=True, eq=False)
class SessionFit:
    """One session's fit.

    Attributes:
        session: where it lies in the recording (:class:`~rdmp_gym.signals.segmentation.sessions.Session`).
        demo: its part of the recording (its own time stamps; of a pose, the position and the orientation's
            tangent coordinates ``[L, p + 3]``).
        fit: the DMP fitted to that part (times from ``session.start``; a :class:`~rdmp_gym.recordings.pose_fit.PoseFit`
            for a pose); ``None`` where the fit refused it.
        error: why the fit refused it; ``None`` when fitted.
    """

    session: Session
    demo: Demonstration
    fit: RecordingFit | PoseFit | None
    error: str | None

    @property
    def recording(self) -> RecordingFit | None:
        """The recording's fit behind ``fit`` (segmentation, ``stop_at``; of a pose, its ``recording``)."""
        return self.fit.recording if isinstance(self.fit, PoseFit) else self.fit

    def report(self) -> dict[str, float | None]:
        """How well ``fit`` reproduces ``demo``: :func:`~rdmp_gym.recordings.recording_fit.recording_report`, of a pose
        :func:`~rdmp_gym.recordings.pose_fit.pose_report`. Raises ``ValueError`` (with ``error``) where the fit refused
        the session, or where it holds too few whole cycles to measure."""
        if self.fit is None:
            raise ValueError(self.error)
        if isinstance(self.fit, PoseFit):
            return pose_report(PoseDemonstration(self.demo, self.fit.reference), self.fit)
        return recording_report(self.demo, self.fit)


def fit_sessions(demo: Demonstration, sessions: list[Session] | None = None, **fit_kwargs) -> list[SessionFit]:
    """One :func:`~rdmp_gym.recordings.recording_fit.fit_recording` per session of ``demo`` (in time order).

    Args:
        demo: the recording on an even grid, outliers removed
            (:func:`rdmp_gym.signals.demonstrations.to_demonstration`).
        sessions: its sessions (default: :func:`~rdmp_gym.signals.segmentation.sessions.find_sessions`).
        fit_kwargs: passed on to ``fit_recording`` (``ending``, ``n_periodic``, ``method``, ...); not the hints
            ``period``, ``start``, ``end``, which are a single rhythm's.
    Raises:
        ValueError: a hint of a single rhythm, or no session
            (:func:`~rdmp_gym.signals.segmentation.sessions.find_sessions`).
    """
    _refuse_hints(fit_kwargs)
    fits = []
    for session in find_sessions(demo) if sessions is None else sessions:
        part = session.part(demo)
        try:
            fits.append(SessionFit(session, part, fit_recording(part, **fit_kwargs), None))
        except ValueError as error:
            fits.append(SessionFit(session, part, None, str(error)))
    return fits


def fit_pose_sessions(pose: PoseDemonstration, sessions: list[Session] | None = None,
                      **fit_kwargs) -> list[SessionFit]:
    """One :func:`~rdmp_gym.recordings.pose_fit.fit_pose_recording` per session of a pose recording (in time order): the
    sessions are those of its position, each part keeps the recording's reference orientation.

    Args:
        pose: the pose recording (:class:`~rdmp_gym.dmp.pose.PoseDemonstration`).
        sessions: its sessions (default: :func:`~rdmp_gym.signals.segmentation.sessions.find_sessions` of its position).
        fit_kwargs: as in :func:`fit_sessions`.
    Raises:
        ValueError: a hint of a single rhythm, or no session.
    """
    if not isinstance(pose, PoseDemonstration):
        raise TypeError(f"pose: expected a PoseDemonstration, got {type(pose).__name__}")
    _refuse_hints(fit_kwargs)
    fits = []
    for session in find_sessions(pose.position) if sessions is None else sessions:
        part = session.part(pose.demo)
        try:
            fits.append(SessionFit(session, part, fit_pose_recording(PoseDemonstration(part, pose.reference),
                                                                     **fit_kwargs), None))
        except ValueError as error:
            fits.append(SessionFit(session, part, None, str(error)))
    return fits


def _refuse_hints(fit_kwargs: dict) -> None:
    """Refuse the hints of one rhythm (``period``, ``start``, ``end``) in ``fit_kwargs``, dropping ``None`` ones."""
    for name in ("period", "start", "end"):
        if fit_kwargs.get(name) is not None:
            raise ValueError(f"{name}: a hint for one rhythm; fit the session's part with fit_recording instead")
        fit_kwargs.pop(name, None)


@dataclass(frozen=True, eq=False)
class JointFit:
    """One DMP for several sessions (:func:`fit_joint`).

    Attributes:
        relative: the DMP about the anchor 0 (the rhythm relative to a session's working point), at the common
            period; transient ``k`` is session ``k``'s entry into its rhythm.
        sessions: the sessions, in time order.
        anchors: ``[K, d]`` each session's anchor: the mean of its working point over its full-size rhythm.
        periods: ``[K]`` each session's period (s).
        entries: ``[K]`` where each session's transient starts (s from its part's first sample, ``session.start``).
    """

    relative: RhythmicDMP
    sessions: tuple[Session, ...]
    anchors: np.ndarray
    periods: np.ndarray
    entries: np.ndarray

    @property
    def dmp(self) -> RhythmicDMP:
        """The DMP at the first session's anchor (:meth:`at_session` ``(0)``)."""
        return self.at_session(0)

    def tempo(self, k: int) -> float:
        """The tempo (speed factor of :meth:`RhythmicDMP.rollout <rdmp_gym.dmp.rhythmic.RhythmicDMP.rollout>`) of
        session ``k``: the common period over its own."""
        return float(self.relative.period / self.periods[self._index(k)])

    def at_session(self, k: int) -> RhythmicDMP:
        """The DMP with session ``k``'s anchor, its transients' starts moved with it: ``rollout(t, transient=k,
        tempo=tempo(k))`` reproduces session ``k`` from its entry."""
        anchor = self.anchors[self._index(k)]
        dmp = self.relative
        transients = [replace(transient, start=transient.start + anchor) for transient in dmp.transients]
        return RhythmicDMP(dmp.canonical, dmp.basis, dmp.weights, transients, anchor.copy(), dmp.alpha_z,
                           dmp.amplitude)

    def reproduce(self, k: int, t: np.ndarray) -> np.ndarray:
        """Session ``k`` reproduced ``[T, d]`` at even times ``t [T]`` (s from its part's first sample): from its
        entry (``entries[k]``) on; before it, where the DMP starts."""
        t = np.asarray(t, dtype=float)
        after = t >= self.entries[self._index(k)] - 1e-9
        if not after.any():
            raise ValueError(f"t: expected times reaching session {k}'s entry at {self.entries[k]:.3g} s")
        reproduced = np.empty((t.size, self.relative.n_dims))
        reproduced[after] = self.at_session(k).rollout(t[after] - t[after][0], transient=int(k), tempo=self.tempo(k))
        reproduced[~after] = reproduced[after][0]
        return reproduced

    def _index(self, k: int) -> int:
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or not 0 <= k < len(self.sessions):
            raise ValueError(f"k: expected a session index in [0, {len(self.sessions)}), got {k!r}")
        return int(k)


def fit_joint(demo: Demonstration, sessions: list[Session] | None = None, *, n_periodic: int = 40,
              n_transient: int = 20, smoothness: float = SMOOTHNESS, **fit_kwargs) -> JointFit:
    """One DMP fitted to the sessions of ``demo`` together (see the module docstring).

    Args:
        demo: the recording on an even grid, outliers removed
            (:func:`rdmp_gym.signals.demonstrations.to_demonstration`).
        sessions: its sessions (default: :func:`~rdmp_gym.signals.segmentation.sessions.find_sessions`).
        n_periodic, n_transient, smoothness: as for :func:`~rdmp_gym.recordings.recording_fit.fit_recording`.
        fit_kwargs: passed on to :meth:`RhythmicDMP.fit <rdmp_gym.dmp.rhythmic.RhythmicDMP.fit>` (``method``, ...); not
            the hints of one rhythm (``period``, ``start``, ``end``) nor ``ending``.
    Raises:
        ValueError: a hint of one rhythm, no session, or sessions whose periods differ by more than
            :data:`~rdmp_gym.signals.segmentation.sessions.SAME_PERIOD` (they do not share one rhythm).
    """
    _refuse_hints(fit_kwargs)
    if fit_kwargs.pop("ending", None):
        raise ValueError("ending: the joint fit encodes the rhythm only; fit_sessions fits each session's ending")
    sessions = tuple(find_sessions(demo) if sessions is None else sessions)
    periods = np.array([session.segmentation.period for session in sessions])
    if periods.max() > (1.0 + SAME_PERIOD) * periods.min():
        raise ValueError(f"sessions: their periods ({', '.join(f'{p:.3g}' for p in periods)} s) differ by more than "
                         f"{SAME_PERIOD:.0%}: they do not share one rhythm; fit each on its own (fit_sessions)")
    period = float(np.mean(periods))
    rhythms = [_relative_rhythm(session.part(demo), session.segmentation, period) for session in sessions]
    relative = RhythmicDMP.fit([rhythm for rhythm, _, _, _ in rhythms], n_periodic=n_periodic,
                               n_transient=n_transient, period=period,
                               segmentations=[Segmentation(period, length, np.zeros(demo.n_dims))
                                              for _, length, _, _ in rhythms],
                               **{**FADE_BEFORE_T, "smoothness": smoothness, **fit_kwargs})
    return JointFit(relative, sessions, np.array([anchor for _, _, anchor, _ in rhythms]), periods,
                    np.array([entry for _, _, _, entry in rhythms]))


def _relative_rhythm(part: Demonstration, seg, period: float) -> tuple[Demonstration, float, np.ndarray, float]:
    """One session's demonstration for the joint fit: its rhythm minus its working point, from
    :data:`~rdmp_gym.recordings.recording_fit.ENTRY_PERIODS` periods before the full-size rhythm to its end, its cycles
    stretched to their mean period (:func:`~rdmp_gym.recordings.recording_fit.normalise_tempo`) and the whole to
    ``period``. Returns it, its entry's length (s, at ``period``), its anchor ``[d]`` and where it starts (s in
    ``part``)."""
    normal, _ = normalise_tempo(part, seg)
    seg = segment_rhythm(normal, period=seg.period)
    t = normal.t - normal.t[0]
    entry = max(seg.rhythm_start - ENTRY_PERIODS * seg.period, 0.0)
    rows = (t >= entry - 0.5 * normal.dt) & (t <= seg.rhythm_end + 0.5 * normal.dt)
    stretch = period / seg.period
    full = (t >= seg.rhythm_start) & (t <= seg.rhythm_end)
    rhythm = Demonstration((t[rows] - t[rows][0]) * stretch, normal.Y[rows] - seg.slow[rows], name=part.name)
    return rhythm, (seg.rhythm_start - t[rows][0]) * stretch, seg.slow[full].mean(axis=0), float(t[rows][0])


def joint_report(demo: Demonstration, joint: JointFit) -> list[dict[str, float]]:
    """How well ``joint`` reproduces each of its sessions in ``demo`` (m): per session its ``period``, ``tempo``,
    ``cycle_variation`` and ``cycle_error`` (as in :func:`~rdmp_gym.recordings.recording_fit.recording_report`: the
    session's cycles, relative to its working point, against their mean and against the reproduction's mean cycle) and
    ``error_ratio``."""
    rows = []
    for k, session in enumerate(joint.sessions):
        part, seg = session.part(demo), session.segmentation
        t = part.t - part.t[0]
        slow = local_fit(part, seg.period)[0]
        variation, error = cycle_figures(t, part.Y - slow, joint.reproduce(k, t), seg.period, seg.rhythm_start,
                                         seg.rhythm_end)
        rows.append({"period": float(joint.periods[k]), "tempo": joint.tempo(k), "cycle_variation": variation,
                     "cycle_error": error, "error_ratio": error / max(variation, 1e-12)})
    return rows
