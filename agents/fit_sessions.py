"""``rdmp-gym fit --demo`` on a recording with several sessions (rhythms separated by departures or rests): one
DMP per session (``dmp-1.json``, ``dmp-2.json``, ...) or, with ``--sessions joint``, one DMP for all of them
(``dmp.json``, each session's anchor in ``report.json``); a summary table and ``report.json``. A pose recording's
sessions are fitted one pose DMP each."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

import numpy as np

from rdmp_gym import Demonstration, save_dmp
from rdmp_gym.dmp.pose import ORIENTATION_DIMS, PoseDemonstration
from rdmp_gym.recordings.pose_fit import PoseFit
from rdmp_gym.recordings.recording_fit import RecordingFit, constant_columns
from rdmp_gym.recordings.session_fit import SessionFit, fit_joint, fit_pose_sessions, fit_sessions, joint_report
from rdmp_gym.signals.segmentation.sessions import Session, find_sessions

__all__ = ["fit_joint_command", "fit_pose_sessions_command", "fit_sessions_command", "several_sessions"]


def several_sessions(demo: Demonstration) -> list[Session] | None:
    """The sessions of ``demo`` when it holds more than one, else ``None`` (one or none: the plain fit)."""
    try:
        sessions = find_sessions(demo)
    except ValueError:
        return None
    return sessions if len(sessions) > 1 else None


def fit_sessions_command(demo: Demonstration, sessions: list[Session], hints: dict, out: Path,
                         plots: ModuleType | None) -> None:
    """Fit each of the ``sessions`` of ``demo`` with the fit's ``hints`` (keywords of
    :func:`~rdmp_gym.recordings.recording_fit.fit_recording`, without the hints of one rhythm); write ``dmp-K.json``,
    ``report.json`` (and ``fit-K.png``) into ``out``; print what was found. Raises ``ValueError`` when no
    session could be fitted."""
    _write_session_fits(demo.name, fit_sessions(demo, sessions, **hints), out, plots)


def fit_pose_sessions_command(pose: PoseDemonstration, sessions: list[Session], hints: dict, out: Path,
                              plots: ModuleType | None) -> None:
    """:func:`fit_sessions_command` for a pose recording: one pose DMP per session, the orientation's figures
    (degrees) beside the position's."""
    _write_session_fits(pose.demo.name, fit_pose_sessions(pose, sessions, **hints), out, plots)


def _write_session_fits(name: str, fits: list[SessionFit], out: Path, plots: ModuleType | None) -> None:
    """Write each fitted session's ``dmp-K.json`` (and ``fit-K.png``) and ``report.json`` into ``out``; print
    the summary table. Raises ``ValueError`` when no session could be fitted."""
    out.mkdir(parents=True, exist_ok=True)
    pose = any(isinstance(item.fit, PoseFit) for item in fits)
    print(f"{name}: {len(fits)} sessions (rhythms separated by departures or rests), one DMP each")
    print(f"{'session':>7} {'part (s)':>13} {'rhythm (s)':>13} {'period (s)':>10} {'error ratio':>11} "
          f"{'accel ratio':>11}" + (f" {'orient. ratio':>13} {'ang. accel ratio':>16}" if pose else "") + "  DMP")
    rows = []
    for k, item in enumerate(fits, start=1):
        session = item.session
        row = {"session": k, "start": session.start, "stop": session.stop, "rhythm_onset": session.rhythm_onset,
               "rhythm_stop": session.rhythm_stop}
        span = f"{session.start:6.2f}-{session.stop:6.2f} {session.rhythm_onset:6.2f}-{session.rhythm_stop:6.2f}"
        try:
            report = item.report()
        except ValueError as error:         # refused, or too few whole cycles to measure
            rows.append({**row, "error": str(error)})
            print(f"{k:>7} {span} refused: {error}")
            continue
        path = out / f"dmp-{k}.json"
        save_dmp(item.fit.dmp, path)
        fit = item.recording
        seg = fit.segmentation
        positions = item.demo.Y[:, :item.demo.n_dims - ORIENTATION_DIMS] if pose else item.demo.Y
        rows.append({**row, "dmp": path.name, "period": seg.period, "rhythm_start": session.start + seg.rhythm_start,
                     "rhythm_end": session.start + seg.rhythm_end, "stop_at": fit.stop_at, **report,
                     "constant_columns": constant_columns(positions)})
        orientation = "" if not pose else f" {'constant':>13} {'-':>16}" if report["orientation_constant"] else \
            f" {report['orientation_error_ratio']:13.2f} {report['angular_acceleration_ratio']:16.2f}"
        print(f"{k:>7} {span} {seg.period:10.3f} {report['error_ratio']:11.2f} {report['acceleration_ratio']:11.2f}"
              f"{orientation}  {path.name}")
        if plots is not None:
            plots.plot_recording_fit(item.demo.t - item.demo.t[0], positions, _reproduce(item.fit),
                                     out / f"fit-{k}.png", title=f"{name}, session {k}: recording vs DMP")
    (out / "report.json").write_text(json.dumps({"sessions": rows}, indent=2) + "\n")
    print(f"times in s from the recording's first sample; each DMP's own time starts at its part's start. "
          f"wrote {len(rows) - sum('error' in row for row in rows)} DMPs and {out / 'report.json'}")
    if all("error" in row for row in rows):
        raise ValueError(f"demo: none of its {len(fits)} sessions could be fitted (see the table)")


def _reproduce(fit: RecordingFit | PoseFit) -> Callable[[np.ndarray], np.ndarray]:
    """The reproduced position ``[T, p]`` at times ``t [T]``."""
    return (lambda t: fit.reproduce(t).position) if isinstance(fit, PoseFit) else fit.reproduce


def fit_joint_command(demo: Demonstration, sessions: list[Session], hints: dict, out: Path,
                      plots: ModuleType | None) -> None:
    """Fit one DMP to all the ``sessions`` of ``demo`` (:func:`~rdmp_gym.recordings.session_fit.fit_joint`, with the
    fit's ``hints`` but those of one rhythm and ``ending``); write ``dmp.json`` (at the first session's anchor),
    ``report.json`` (each session's anchor, start, tempo and transient, and how well it is reproduced) and
    ``fit-K.png``; print what was found."""
    keywords = {key: value for key, value in hints.items() if key not in ("period", "start", "end", "ending")}
    joint = fit_joint(demo, sessions, **keywords)
    report = joint_report(demo, joint)
    out.mkdir(parents=True, exist_ok=True)
    save_dmp(joint.dmp, out / "dmp.json")
    print(f"{demo.name}: {len(sessions)} sessions (rhythms separated by departures or rests) fitted as one rhythm, "
          f"period {joint.relative.period:.3f} s; one DMP with each session's anchor")
    print(f"{'session':>7} {'part (s)':>13} {'rhythm (s)':>13} {'period (s)':>10} {'tempo':>6} {'error ratio':>11}"
          f"  anchor (m)")
    rows = []
    for k, (session, figures) in enumerate(zip(joint.sessions, report, strict=True)):
        row = {"session": k + 1, "transient": k, "start": session.start, "stop": session.stop,
               "rhythm_onset": session.rhythm_onset, "rhythm_stop": session.rhythm_stop,
               "entry": session.start + float(joint.entries[k]), "anchor": joint.anchors[k].tolist(),
               "y0": joint.at_session(k).starts[k].tolist(), **figures}
        rows.append(row)
        print(f"{k + 1:>7} {session.start:6.2f}-{session.stop:6.2f} {session.rhythm_onset:6.2f}-"
              f"{session.rhythm_stop:6.2f} {figures['period']:10.3f} {figures['tempo']:6.3f} "
              f"{figures['error_ratio']:11.2f}  {_vector(joint.anchors[k])}")
        if plots is not None:
            part = session.part(demo)
            plots.plot_recording_fit(part.t - part.t[0], part.Y, lambda t, k=k: joint.reproduce(k, t),
                                     out / f"fit-{k + 1}.png", title=f"{demo.name}, session {k + 1}: joint DMP")
    (out / "report.json").write_text(json.dumps({"period": joint.relative.period, "dmp": "dmp.json",
                                                 "sessions": rows}, indent=2) + "\n")
    print("session K from its entry: load_dmp('dmp.json').rollout(t, transient=K - 1, anchor=anchor, y0=y0, "
          f"tempo=tempo) with the session's anchor, y0 and tempo from {out / 'report.json'}; wrote {out / 'dmp.json'}")


def _vector(values) -> str:
    return "(" + ", ".join(f"{value:.3f}" for value in values) + ")"
