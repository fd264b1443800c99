"""Pose recordings from CSV files: a time column, position columns and the orientation as ``qw, qx, qy, qz``."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from ..dmp.pose import PoseDemonstration

__all__ = ["QUATERNION_COLUMNS", "read_pose_csv", "write_pose_csv"]

QUATERNION_COLUMNS = ("qw", "qx", "qy", "qz")
"""The names of a pose CSV's orientation columns: a unit quaternion, scalar first (either sign per row)."""


def read_pose_csv(path: str | Path, time_column: str = "t", rate: float = 100.0) -> PoseDemonstration | None:
    """The pose recording in ``path`` on an even grid at ``rate`` Hz (:meth:`PoseDemonstration.from_samples`),
    or ``None`` when the file has no orientation columns.

    The header names the columns: ``time_column`` (s), the quaternion's :data:`QUATERNION_COLUMNS` (all four or
    none) and the position (every other column, in file order, m). ``ValueError`` for a partial quaternion, a
    missing time column, no position column, a non-numeric value or a row that is not a unit quaternion.
    """
    path = Path(path)
    with path.open(encoding="utf-8-sig", newline="") as handle:
        header = [name.strip() for name in next(csv.reader(handle), [])]
    present = [name for name in QUATERNION_COLUMNS if name in header]
    if not present:
        return None
    if len(present) < len(QUATERNION_COLUMNS):
        missing = [name for name in QUATERNION_COLUMNS if name not in header]
        raise ValueError(f"path: {path} has the orientation column(s) {present} but lacks {missing}; an orientation "
                         f"needs all of {list(QUATERNION_COLUMNS)} (a unit quaternion, scalar first)")
    if time_column not in header:
        raise ValueError(f"time_column: {time_column!r} is not a column of {path} (columns: {header})")
    positions = [name for name in header if name != time_column and name not in QUATERNION_COLUMNS]
    if not positions:
        raise ValueError(f"path: {path} has no position column beside {time_column!r} and the orientation")
    try:
        data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2, dtype=np.float64, encoding="utf-8-sig")
    except ValueError as error:
        raise ValueError(f"path: {path} holds a non-numeric value: {error}") from error
    if data.shape[1] != len(header):
        raise ValueError(f"path: {path} has {len(header)} header names but {data.shape[1]} columns")
    column = {name: k for k, name in enumerate(header)}
    try:
        return PoseDemonstration.from_samples(data[:, column[time_column]], data[:, [column[n] for n in positions]],
                                              data[:, [column[n] for n in QUATERNION_COLUMNS]], rate, name=path.stem)
    except ValueError as error:
        raise ValueError(f"path: {path}: {error}") from error


def write_pose_csv(path: str | Path, t: np.ndarray, Y: np.ndarray, Q: np.ndarray, time_column: str = "t") -> None:
    """Write stamps ``t [L]`` (s), positions ``Y [L, 3]`` (m) and quaternions ``Q [L, 4]`` as a pose CSV:
    ``time_column, x, y, z, qw, qx, qy, qz`` (17 significant digits), the format :func:`read_pose_csv` reads."""
    np.savetxt(path, np.column_stack([t, Y, Q]), fmt="%.17g", delimiter=",",
               header=",".join([time_column, "x", "y", "z", *QUATERNION_COLUMNS]), comments="")
