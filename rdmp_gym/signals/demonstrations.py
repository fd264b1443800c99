"""Demonstrations: a sampled trajectory ``Y[L, d]`` on an even time grid ``t[L]``, and how samples get in and out.

* :class:`Demonstration`: the container (validated, read-only), its files (CSV, NPZ) and resampling onto an even
  grid; :func:`to_demonstration`: a recorder's samples at uneven stamps, outliers removed
  (:func:`rdmp_gym.signals.filters.despike`), on an even grid.
* :func:`check_frame`: samples in metres and inside the wiping table's reachable box (:data:`TABLE_WORKSPACE`).
* :class:`SyntheticTruth`: the true values a synthetic demonstration carries; the generators themselves are in
  :mod:`rdmp_gym.synthetic.demonstrations`.
"""

from __future__ import annotations

import codecs
import csv
import io
import zipfile
import zlib
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.interpolate import CubicSpline

from rdmp_gym.signals.filters import despike
from rdmp_gym.validation import as_finite_array, check_positive, check_time_grid

__all__ = ["TABLE_WORKSPACE", "Demonstration", "SyntheticTruth", "check_frame", "to_demonstration"]

#: ``(low [3], high [3])`` box (m) in the table frame that the wiping env's paths must stay inside: x, y on
#: the table about the dirt patch centre, z above the table surface.
TABLE_WORKSPACE = ((-0.35, -0.40, -0.05), (0.35, 0.40, 0.30))
_MILLIMETRE_SPAN = 5.0  # m: a demonstration spanning more than this is taken to be in millimetres


def _readonly(array: np.ndarray) -> np.ndarray:
    array = np.array(array, dtype=np.float64)
    array.setflags(write=False)
    return array


@dataclass(frozen=True, eq=False)
class SyntheticTruth:
    """The true values behind a synthetic demonstration.

    Attributes:
        period: period of the periodic part (s).
        transient_length: the signal is exactly periodic for ``t - t[0] >= transient_length`` (s).
        anchor: ``[d]`` mean of the periodic pattern over a whole period.
        clean: ``[L, d]`` the noiseless signal.
        entrance_time: pattern time in ``[0, period)`` at which the demonstration enters the shared
            periodic pattern (at ``t - t[0] = transient_length``).
    """

    period: float
    transient_length: float
    anchor: np.ndarray
    clean: np.ndarray
    entrance_time: float = 0.0

    def __post_init__(self) -> None:
        period = check_positive(self.period, "period")
        transient = float(as_finite_array(self.transient_length, "transient_length", ndim=0))
        if transient < 0.0:
            raise ValueError(f"transient_length: expected >= 0, got {transient!r}")
        entrance = float(as_finite_array(self.entrance_time, "entrance_time", ndim=0))
        if not 0.0 <= entrance < period:
            raise ValueError(f"entrance_time: expected a value in [0, period={period}), "
                             f"got {entrance!r}")
        anchor = as_finite_array(self.anchor, "anchor", ndim=1)
        clean = as_finite_array(self.clean, "clean", ndim=2)
        if clean.shape[1] != anchor.size:
            raise ValueError(f"clean: expected {anchor.size} columns (the size of anchor), "
                             f"got shape {clean.shape}")
        object.__setattr__(self, "period", period)
        object.__setattr__(self, "transient_length", transient)
        object.__setattr__(self, "entrance_time", entrance)
        object.__setattr__(self, "anchor", _readonly(anchor))
        object.__setattr__(self, "clean", _readonly(clean))


@dataclass(frozen=True, eq=False)
class Demonstration:
    """A demonstrated trajectory.

    Attributes:
        t: ``[L]`` time stamps (s), strictly increasing and evenly spaced (relative tolerance 1e-3).
        Y: ``[L, d]`` samples (a 1-D input ``[L]`` is stored as ``[L, 1]``), finite.
        name: a label.
        truth: the true values of a synthetic demonstration, else ``None``.

    ``t`` and ``Y`` are stored as read-only float64 copies.
    """

    t: np.ndarray
    Y: np.ndarray
    name: str = ""
    truth: SyntheticTruth | None = None

    def __post_init__(self) -> None:
        t = check_time_grid(self.t, "t")
        Y = as_finite_array(self.Y, "Y", ndim=(1, 2))
        if Y.ndim == 1:
            Y = Y[:, None]
        if Y.shape[0] != t.size:
            raise ValueError(f"Y: expected {t.size} rows (one per time stamp in t), "
                             f"got shape {Y.shape}")
        if Y.shape[1] == 0:
            raise ValueError("Y: expected at least one column (dimension), got 0")
        if not isinstance(self.name, str):
            raise TypeError(f"name: expected a str, got {type(self.name).__name__}")
        if self.truth is not None:
            if not isinstance(self.truth, SyntheticTruth):
                raise TypeError(f"truth: expected SyntheticTruth or None, "
                                f"got {type(self.truth).__name__}")
            if self.truth.clean.shape != Y.shape:
                raise ValueError(f"truth: clean has shape {self.truth.clean.shape}, "
                                 f"Y has {Y.shape}")
        object.__setattr__(self, "t", _readonly(t))
        object.__setattr__(self, "Y", _readonly(Y))

    @property
    def n_samples(self) -> int:
        """Number of samples ``L``."""
        return int(self.t.size)

    @property
    def n_dims(self) -> int:
        """Number of dimensions ``d``."""
        return int(self.Y.shape[1])

    @property
    def dt(self) -> float:
        """Mean sampling step (s)."""
        return float((self.t[-1] - self.t[0]) / (self.t.size - 1))

    @property
    def duration(self) -> float:
        """``t[-1] - t[0]`` (s)."""
        return float(self.t[-1] - self.t[0])

    def to_csv(self, path: str | Path, *, columns: Sequence[str] | None = None,
               time_column: str = "t") -> None:
        """Write a CSV file: a header row, then one row per sample.

        Columns: ``time_column`` (s), then one column per dimension named ``columns`` (default
        ``y0, y1, ...``). Values are written with 17 significant digits: a round trip is lossless.
        """
        if columns is None:
            names = [f"y{i}" for i in range(self.n_dims)]
        else:
            names = [str(column) for column in columns]
        if len(names) != self.n_dims:
            raise ValueError(f"columns: expected {self.n_dims} names, got {len(names)}")
        for label in [time_column, *names]:
            if not label or any(ch in label for ch in ',"\n\r'):
                raise ValueError(f"columns: invalid column name {label!r}")
        if len(set([time_column, *names])) != self.n_dims + 1:
            raise ValueError(f"columns: column names must be distinct, got {[time_column, *names]}")
        data = np.column_stack([self.t, self.Y])
        np.savetxt(path, data, fmt="%.17g", delimiter=",", header=",".join([time_column, *names]),
                   comments="")

    @classmethod
    def from_csv(cls, path: str | Path, time_column: str = "t", rate: float | None = None) -> Demonstration:
        """Read a CSV file written by :meth:`to_csv` (or any file with that layout).

        The first row names the columns; the column ``time_column`` holds the time (s), every other
        column, in file order, is one dimension of ``Y``. The demonstration is named after the file.
        ``rate`` (Hz) resamples the samples onto an even grid (see :meth:`from_samples`): for uneven
        time stamps, or another rate.
        """
        path = Path(path)
        with _open_text(path) as handle:
            header = next(csv.reader(handle), None)
            if not header:
                raise ValueError(f"path: {path} has no header row")
            header = [name.strip() for name in header]
            repeated = sorted({name for name in header if header.count(name) > 1})
            if repeated:
                raise ValueError(f"path: {path} names the column(s) {repeated} more than once")
            if time_column not in header:
                raise ValueError(f"time_column: {time_column!r} is not a column of {path} "
                                 f"(columns: {header})")
            if len(header) < 2:
                raise ValueError(f"path: {path} needs a time column and at least one data column")
            try:
                data = np.loadtxt(handle, delimiter=",", ndmin=2, dtype=np.float64)
            except ValueError as error:
                raise ValueError(f"path: {path} holds a non-numeric value: {error}") from error
        if data.shape[1] != len(header):
            raise ValueError(f"path: {path} has {len(header)} header names "
                             f"but {data.shape[1]} columns")
        column = header.index(time_column)
        return cls.from_samples(data[:, column], np.delete(data, column, axis=1), name=path.stem, rate=rate)

    @classmethod
    def from_samples(cls, t: np.ndarray, Y: np.ndarray, name: str = "", rate: float | None = None) -> Demonstration:
        """A demonstration from samples ``Y [L, d]`` at time stamps ``t [L]`` (strictly increasing).

        With ``rate`` (Hz) the samples are resampled onto the even grid ``t[0] + k / rate`` within
        ``[t[0], t[-1]]`` by a cubic spline through them (not-a-knot ends): uneven time stamps (a
        recorder's jitter) or another rate. Without it the stamps must already be evenly spaced.
        """
        if rate is None:
            return cls(t=t, Y=Y, name=name)
        rate = check_positive(rate, "rate")
        t = check_time_grid(t, "t", uniform=False, min_length=4)
        Y = as_finite_array(Y, "Y", ndim=(1, 2))
        if Y.shape[0] != t.size:
            raise ValueError(f"Y: expected {t.size} rows (one per time stamp in t), got shape {Y.shape}")
        grid = t[0] + np.arange(int(np.floor((t[-1] - t[0]) * rate + 1e-9)) + 1) / rate
        if grid.size < 2:
            raise ValueError(f"rate: {rate} Hz gives fewer than 2 samples over {t[-1] - t[0]:.3g} s")
        return cls(t=grid, Y=CubicSpline(t, Y, axis=0)(grid), name=name)

    def resample(self, rate: float) -> Demonstration:
        """The demonstration on an even grid at ``rate`` Hz (cubic spline, :meth:`from_samples`);
        ``truth`` is dropped (it belongs to the original samples)."""
        return type(self).from_samples(self.t, self.Y, name=self.name, rate=rate)

    def check_frame(self, low: Sequence[float] = TABLE_WORKSPACE[0], high: Sequence[float] = TABLE_WORKSPACE[1],
                    *, centre_dims: Sequence[int] = (), name: str = "demonstration") -> None:
        """Raise ``ValueError`` unless the samples lie in the box ``[low, high]`` (m); see :func:`check_frame`."""
        check_frame(self.Y, low, high, centre_dims=centre_dims, name=name)

    def to_npz(self, path: str | Path) -> None:
        """Write an ``.npz`` archive: arrays ``t`` ``[L]``, ``Y`` ``[L, d]``, ``name`` (0-d str).

        As with ``numpy.savez``, ``.npz`` is appended to a path without that suffix.
        """
        np.savez(path, t=self.t, Y=self.Y, name=np.array(self.name))

    @classmethod
    def from_npz(cls, path: str | Path) -> Demonstration:
        """Read an ``.npz`` archive: arrays ``t`` ``[L]``, ``Y`` ``[L, d]`` (``name`` optional)."""
        path = Path(path)
        try:
            data = np.load(path, allow_pickle=False)
        except (OSError, ValueError, EOFError, zipfile.BadZipFile) as error:
            raise ValueError(f"path: {path} is not a readable .npz archive ({error})") from error
        if not isinstance(data, np.lib.npyio.NpzFile):
            raise ValueError(f"path: {path} is a single .npy array, not an .npz archive with arrays t and Y")
        with data:
            missing = [key for key in ("t", "Y") if key not in data.files]
            if missing:
                raise ValueError(f"path: {path} lacks the array(s) {missing} (has {data.files})")
            try:
                name = str(data["name"]) if "name" in data.files else path.stem
                t, Y = data["t"], data["Y"]
            except (OSError, ValueError, EOFError, zipfile.BadZipFile, zlib.error) as error:
                raise ValueError(f"path: {path} is damaged ({error})") from error
        return cls(t=t, Y=Y, name=name)


def _open_text(path: Path) -> io.StringIO:
    """The text of ``path``: UTF-8 (with or without the BOM spreadsheets write) or UTF-16 with a BOM."""
    raw = path.read_bytes()
    encoding = "utf-16" if raw[:2] in (codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE) else "utf-8-sig"
    try:
        return io.StringIO(raw.decode(encoding), newline="")
    except UnicodeDecodeError as error:
        raise ValueError(f"path: {path} is not UTF-8 or UTF-16 text ({error.reason} at byte {error.start})") \
            from error


def check_frame(Y: np.ndarray, low: Sequence[float], high: Sequence[float], *, centre_dims: Sequence[int] = (),
                name: str = "demonstration") -> None:
    """Check that samples ``Y [L, d]`` are in metres and inside the box ``[low, high]`` (``[d]`` each, m).

    ``centre_dims`` are measured from the middle of their range (dimensions that a user of the samples
    re-anchors, e.g. x and y of a wiping pattern that is moved onto the dirt patch). Raises ``ValueError``
    naming ``name``, the dimension and the range found: a span over 5 m is taken for millimetres, any
    other excursion for the wrong frame (for the wiping env: x, y on the table, z above its surface).
    """
    Y = as_finite_array(Y, name, ndim=2)
    low_box, high_box = as_finite_array(low, "low", ndim=1), as_finite_array(high, "high", ndim=1)
    if low_box.shape != (Y.shape[1],) or high_box.shape != low_box.shape or np.any(low_box >= high_box):
        raise ValueError(f"low, high: expected {Y.shape[1]} values each with low < high")
    span = np.ptp(Y, axis=0)
    if np.any(span > _MILLIMETRE_SPAN):
        k = int(np.argmax(span))
        raise ValueError(f"{name}: dimension {k} spans {span[k]:.4g}, which looks like millimetres; "
                         "expected metres (divide the samples by 1000)")
    shifted = Y.copy()
    for k in centre_dims:
        shifted[:, k] -= 0.5 * (Y[:, k].min() + Y[:, k].max())
    below, above = shifted.min(axis=0) < low_box, shifted.max(axis=0) > high_box
    if np.any(below | above):
        k = int(np.argmax(below | above))
        where = "about the middle of its range " if k in centre_dims else ""
        raise ValueError(f"{name}: dimension {k} ranges {where}from {shifted[:, k].min():.4g} to "
                         f"{shifted[:, k].max():.4g} m, outside the reachable [{low_box[k]:.4g}, {high_box[k]:.4g}] m; "
                         "expected the table frame in metres (x, y on the table, z above the table surface)")


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
