"""Fit each session of a recording with several: one DMP per rhythm, each with its own approach and ending.

:func:`rdmp_gym.segmentation.sessions.find_sessions` cuts the recording between its sessions; each part is then
a whole recording of its own (rest or motion, approach, rhythm, departure, rest) for
:func:`rdmp_gym.recording_fit.fit_recording`.
"""

from __future__ import annotations

from dataclasses import dataclass

from .demonstrations import Demonstration
from .recording_fit import RecordingFit, fit_recording
from .segmentation.sessions import Session, find_sessions

__all__ = ["SessionFit", "fit_sessions"]


@dataclass(frozen=True, eq=False)
class SessionFit:
    """One session's fit.

    Attributes:
        session: where it lies in the recording (:class:`~rdmp_gym.segmentation.sessions.Session`).
        demo: its part of the recording (its own time stamps).
        fit: the DMP fitted to that part (times from ``session.start``); ``None`` where the fit refused it.
        error: why the fit refused it; ``None`` when fitted.
    """

    session: Session
    demo: Demonstration
    fit: RecordingFit | None
    error: str | None


def fit_sessions(demo: Demonstration, sessions: list[Session] | None = None, **fit_kwargs) -> list[SessionFit]:
    """One :func:`~rdmp_gym.recording_fit.fit_recording` per session of ``demo`` (in time order).

    Args:
        demo: the recording on an even grid, outliers removed (:func:`rdmp_gym.demonstrations.to_demonstration`).
        sessions: its sessions (default: :func:`~rdmp_gym.segmentation.sessions.find_sessions`).
        fit_kwargs: passed on to ``fit_recording`` (``ending``, ``n_periodic``, ``method``, ...); not the hints
            ``period``, ``start``, ``end``, which are a single rhythm's.
    Raises:
        ValueError: a hint of a single rhythm, or no session (:func:`~rdmp_gym.segmentation.sessions.find_sessions`).
    """
    for name in ("period", "start", "end"):
        if fit_kwargs.get(name) is not None:
            raise ValueError(f"{name}: a hint for one rhythm; fit the session's part with fit_recording instead")
        fit_kwargs.pop(name, None)
    fits = []
    for session in find_sessions(demo) if sessions is None else sessions:
        part = session.part(demo)
        try:
            fits.append(SessionFit(session, part, fit_recording(part, **fit_kwargs), None))
        except ValueError as error:
            fits.append(SessionFit(session, part, None, str(error)))
    return fits
