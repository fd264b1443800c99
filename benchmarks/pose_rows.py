"""Rows of ``bench_recordings.py`` for pose recordings (position and orientation): the position's figures and the
orientation's (cycle error against the recording's cycle-to-cycle variation in degrees, peak angular acceleration
against the smoothed recording's and, where known, the noise-free one's), and whether ``rdmp-gym fit --demo``
fits the pose CSV; in a recording with several sessions also each session's pose fit."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
from rdmp_gym.agents.cli import main as cli_main

from rdmp_gym.dmp import quaternion
from rdmp_gym.dmp.pose import PoseDemonstration
from rdmp_gym.recordings.pose_fit import fit_pose_recording, pose_report, smoothed_peak_angular_acceleration
from rdmp_gym.recordings.pose_io import write_pose_csv
from rdmp_gym.recordings.session_fit import fit_pose_sessions
from rdmp_gym.signals.segmentation.sessions import find_sessions

__all__ = ["pose_row", "print_pose_row", "read_orientation", "summary"]

_TARGETS = (("error_ratio", 1.5), ("orientation_error_ratio", 1.5), ("acceleration_ratio", 1.5),
            ("angular_acceleration_ratio", 1.5))


def read_orientation(path: Path, rate: float) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """``(t [L], positions [L, 3], quaternions [L, 4])`` of a CSV with ``qw, qx, qy, qz`` columns or a 12-column
    pose file (rows of a 3x4 transform, row-major, at ``rate`` Hz); ``None`` for a file without orientation."""
    if path.suffix.lower() == ".txt":
        data = np.loadtxt(path)
        rotation = data[:, [0, 1, 2, 4, 5, 6, 8, 9, 10]].reshape(-1, 3, 3)
        return np.arange(data.shape[0]) / rate, data[:, [3, 7, 11]], quaternion.from_matrix(rotation)
    data = np.genfromtxt(path, delimiter=",", names=True)
    names = data.dtype.names
    if not {"qw", "qx", "qy", "qz"} <= set(names):
        return None
    return (np.asarray(data[names[0]]), np.column_stack([data[n] for n in ("x", "y", "z")]),
            np.column_stack([data[n] for n in ("qw", "qx", "qy", "qz")]))


def pose_row(name: str, t: np.ndarray, Y: np.ndarray, Q: np.ndarray, truth: dict | None,
             clean: np.ndarray | None = None) -> dict:
    """One row: the pose fit's figures (``truth``: known ``period``, ``start``, ``end`` in s; each session's too
    where the recording holds several), the noise-free orientation's peak angular acceleration where
    ``clean [L, 4]`` is known, and the CLI on the pose CSV."""
    row, pose = {"recording": name}, None
    try:
        pose = PoseDemonstration.from_samples(t, Y, Q, name=name)
        result = fit_pose_recording(pose)
        seg = result.recording.segmentation
        row.update(period=seg.period, start=seg.rhythm_start, end=seg.rhythm_end, **pose_report(pose, result),
                   orientation_range=float(np.degrees(np.max(np.linalg.norm(pose.tangent.Y, axis=1)))))
    except ValueError as error:
        row["error"] = str(error)
    if pose is not None:                    # read, whether or not the whole recording was fitted
        row.update(_session_figures(pose))
    for key, value in (truth or {}).items():
        row[f"true_{key}"] = value
    if clean is not None and "peak_angular_acceleration" in row:
        noise_free = PoseDemonstration.from_samples(t, Y, clean, outliers=False)
        peak = smoothed_peak_angular_acceleration(noise_free.tangent, noise_free.reference)
        row.update(clean_peak_angular_acceleration=peak,
                   clean_angular_acceleration_ratio=row["peak_angular_acceleration"] / peak)
    with tempfile.TemporaryDirectory() as folder:
        csv_path = Path(folder) / "pose.csv"
        write_pose_csv(csv_path, t, Y, Q)
        row["cli"] = cli_main(["fit", "--demo", str(csv_path), "--out", str(Path(folder) / "out")]) == 0
    return row


def _session_figures(pose: PoseDemonstration) -> dict:
    """``{"sessions": [...]}``: each session's pose fit (its rhythm's onset and stop, period, the position's and
    the orientation's ratios, or why it was refused) where the recording holds several; ``{}`` otherwise."""
    try:
        sessions = find_sessions(pose.position)
    except ValueError:
        return {}
    if len(sessions) < 2:
        return {}
    rows = []
    for item in fit_pose_sessions(pose, sessions):
        row = {"rhythm_onset": item.session.rhythm_onset, "rhythm_stop": item.session.rhythm_stop}
        try:
            report = item.report()
            row.update(period=item.recording.segmentation.period, **{key: report[key] for key, _ in _TARGETS})
        except ValueError as error:
            row["error"] = str(error)
        rows.append(row)
    return {"sessions": rows}


def print_pose_row(row: dict) -> None:
    """One line per row."""
    if "error" in row:
        print(f"{row['recording']:>24}: pose FAILED ({row['error']}); CLI {'ok' if row['cli'] else 'failed'}")
        return
    clean = (f" (clean {row['clean_angular_acceleration_ratio']:.2f})" if "clean_angular_acceleration_ratio" in row
             else "")
    print(f"{row['recording']:>24}: pose | position {1000 * row['cycle_error']:.2f} / "
          f"{1000 * row['cycle_variation']:.2f} mm = {row['error_ratio']:.2f}, accel {row['acceleration_ratio']:.2f} | "
          f"orientation (range {row['orientation_range']:.0f} deg) {row['orientation_error']:.2f} / "
          f"{row['orientation_variation']:.2f} deg = {row['orientation_error_ratio']:.2f}, "
          f"rms {row['orientation_rmse']:.2f} deg, angular accel {row['angular_acceleration_ratio']:.2f}{clean} | "
          f"CLI {'ok' if row['cli'] else 'failed'}")
    for k, session in enumerate(row.get("sessions", []), start=1):
        figures = session.get("error") or ", ".join(f"{key} {session[key]:.2f}" for key, _ in _TARGETS)
        print(f"{'session ' + str(k):>24}: {session['rhythm_onset']:.2f}-{session['rhythm_stop']:.2f} s | {figures}")


def summary(title: str, rows: list[dict]) -> None:
    """How many pose rows meet each target, and the worst figure."""
    fitted = [row for row in rows if "error" not in row]
    sessions = [session for row in rows for session in row.get("sessions", []) if "error" not in session]
    print(f"{title} (pose): {len(fitted)} of {len(rows)} fitted, CLI ok on {sum(row['cli'] for row in rows)}; "
          f"{len(sessions)} sessions fitted one by one in the recordings with several")
    for key, limit in _TARGETS:
        values = [row[key] for row in fitted] + [session[key] for session in sessions]
        if values:
            print(f"  {key}: {sum(v <= limit for v in values)} of {len(values)} <= {limit:g} (worst {max(values):.4g})")
