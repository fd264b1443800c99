"""Save and load DMPs as JSON (lossless: floats are written with ``repr`` precision).

Format ``rdmp-gym/rhythmic-dmp``, version 1. Top-level keys:

* ``format`` (str), ``version`` (int)
* ``canonical``: ``period, mu, eta, alpha, beta, tempo``
* ``transformation``: ``alpha_z`` (``beta_z = alpha_z / 4``)
* ``anchor``: ``[d]``
* ``amplitude``: ``[d]`` (factors that scale the movement about the anchor)
* ``basis``: ``periodic_centres [N]``, ``periodic_widths [N]``, ``transient_centres [M, 2]``,
  ``transient_widths [M]``, ``transient_sizes [K]``, ``fading {mu1, mu2, k, delta, floor}``
* ``weights``: ``[d, D]`` (periodic columns first, then each transient's)
* ``transients``: K objects ``{phi0, r0, length, entrance_phase, start [d], start_velocity [d]}``
* ``stop`` (optional, absent for a DMP without an end of the movement): ``{exit_phase, length, blend_start,
  goal [d], centres [S, 2], widths [S], weights [d, S], fading {nu1, nu2, k, delta}}``
* ``sweep`` (optional, absent for a DMP whose anchor stays in place): ``{times [K + 1], points [K, d]}``
  (:class:`~rdmp_gym.dmp.sweep.Sweep`)
* ``orientation`` (optional, a :class:`~rdmp_gym.dmp.pose.PoseDMP`): ``{reference [4]}``, the unit quaternion
  (w, x, y, z) about which the last three dimensions are the orientation's tangent coordinates
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, fields
from pathlib import Path

import numpy as np

from .basis import NORMALISATION_EPSILON, BasisSet, Fading
from .canonical import CanonicalSystem
from .ending import Ending, StopFading
from .pose import ORIENTATION_DIMS, PoseDMP
from .quaternion import check_unit
from .rhythmic import RhythmicDMP, TransientStart
from .sweep import Sweep

__all__ = ["FORMAT", "VERSION", "dmp_from_dict", "dmp_to_dict", "load_dmp", "save_dmp"]

FORMAT = "rdmp-gym/rhythmic-dmp"
VERSION = 1


def dmp_to_dict(dmp: RhythmicDMP | PoseDMP) -> dict:
    """A JSON-ready dictionary of every number that defines ``dmp``."""
    if isinstance(dmp, PoseDMP):
        return {**dmp_to_dict(dmp.dmp), "orientation": {"reference": dmp.reference.tolist()}}
    basis = dmp.basis
    data = {
        "format": FORMAT,
        "version": VERSION,
        "canonical": asdict(dmp.canonical),
        "transformation": {"alpha_z": dmp.alpha_z},
        "anchor": dmp.anchor.tolist(),
        "amplitude": dmp.amplitude.tolist(),
        "basis": {
            "periodic_centres": basis.periodic_centres.tolist(),
            "periodic_widths": basis.periodic_widths.tolist(),
            "transient_centres": basis.transient_centres.tolist(),
            "transient_widths": basis.transient_widths.tolist(),
            "transient_sizes": list(basis.transient_sizes),
            "fading": asdict(basis.fading),
        },
        "weights": dmp.weights.tolist(),
        "transients": [{"phi0": s.phi0, "r0": s.r0, "length": s.length, "entrance_phase": s.entrance_phase,
                        "start": s.start.tolist(), "start_velocity": s.start_velocity.tolist()}
                       for s in dmp.transients],
    }
    if dmp.ending is not None:
        data["stop"] = dmp.ending.to_dict()
    if dmp.sweep is not None:
        data["sweep"] = dmp.sweep.to_dict()
    return data


class _Reader:
    """Typed access to one JSON object; every error is a ``ValueError`` naming the field (dotted path)."""

    def __init__(self, value: object, where: str) -> None:
        if not isinstance(value, dict):
            raise ValueError(f"{where}: expected a JSON object, got {type(value).__name__}")
        self.value, self.where = value, where

    def field(self, key: str, default: object = None, required: bool = True) -> object:
        if key not in self.value:
            if required:
                raise ValueError(f"{self.where}.{key}: missing")
            return default
        return self.value[key]

    def only(self, keys: tuple[str, ...]) -> None:
        unknown = sorted(set(self.value) - set(keys))
        if unknown:
            raise ValueError(f"{self.where}: unknown field(s) {unknown}; expected some of {list(keys)}")

    def number(self, key: str, *, positive: bool = False, default: float | None = None) -> float:
        value = self.field(key, default, required=default is None)
        name = f"{self.where}.{key}"
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"{name}: expected a number, got {type(value).__name__}")
        if not math.isfinite(value) or (positive and value <= 0):
            raise ValueError(f"{name}: expected a finite{' positive' if positive else ''} number, got {value!r}")
        return float(value)

    def integer(self, key: str, *, low: int, default: int | None = None) -> int:
        value = self.field(key, default, required=default is None)
        if isinstance(value, bool) or not isinstance(value, int) or value < low:
            raise ValueError(f"{self.where}.{key}: expected an integer >= {low}, got {value!r}")
        return value

    def array(self, key: str, shape: tuple[int | None, ...], *, positive: bool = False) -> np.ndarray:
        """A finite float array of ``shape`` (None = any size) from nested JSON lists of numbers."""
        name = f"{self.where}.{key}"
        value = self.field(key)

        def numbers(item: object, depth: int) -> bool:
            if depth == len(shape):
                return not isinstance(item, bool) and isinstance(item, (int, float))
            return isinstance(item, list) and all(numbers(x, depth + 1) for x in item)

        if not numbers(value, 0):
            raise ValueError(f"{name}: expected {len(shape)}-level nested lists of numbers")
        array = np.array(value, dtype=np.float64)
        if len(shape) == 2 and array.size == 0:
            array = array.reshape(0, shape[1] or 0)
        if array.ndim != len(shape) or any(n is not None and n != m for n, m in zip(shape, array.shape, strict=True)):
            expected = "[" + ", ".join("*" if n is None else str(n) for n in shape) + "]"
            raise ValueError(f"{name}: expected shape {expected}, got {list(array.shape)}")
        if not np.all(np.isfinite(array)):
            raise ValueError(f"{name}: contains NaN or infinite values")
        if positive and np.any(array <= 0.0):
            raise ValueError(f"{name}: expected positive values")
        return array


def dmp_from_dict(data: dict) -> RhythmicDMP | PoseDMP:
    """Rebuild a DMP from :func:`dmp_to_dict`'s output (a :class:`~rdmp_gym.dmp.pose.PoseDMP` where it has an
    ``orientation``).

    Every field is checked (type, finiteness, sign, shapes and sizes consistent with each other);
    a problem is a ``ValueError`` that names the field, e.g. ``dmp.transients[0].start``.
    """
    top = _Reader(data, "dmp")
    if data.get("format") != FORMAT:
        raise ValueError(f"dmp.format: not an rdmp-gym DMP file (format {data.get('format')!r})")
    if data.get("version") != VERSION:
        raise ValueError(f"dmp.version: unsupported format version {data.get('version')!r}; this library reads "
                         f"{VERSION}")
    top.only(("format", "version", "canonical", "transformation", "anchor", "amplitude", "basis", "weights",
              "transients", "stop", "sweep", "orientation"))
    canonical = _Reader(top.field("canonical"), "dmp.canonical")
    canonical.only(tuple(f.name for f in fields(CanonicalSystem)))
    defaults = {f.name: f.default for f in fields(CanonicalSystem) if f.name != "period"}
    system = CanonicalSystem(period=canonical.number("period", positive=True),
                             **{k: canonical.number(k, positive=True, default=v) for k, v in defaults.items()})
    transformation = _Reader(top.field("transformation"), "dmp.transformation")
    transformation.only(("alpha_z",))
    alpha_z = transformation.number("alpha_z", positive=True)
    anchor = top.array("anchor", (None,))
    d = anchor.size
    if d == 0:
        raise ValueError("dmp.anchor: expected at least one dimension")
    amplitude = top.array("amplitude", (d,))

    basis = _Reader(top.field("basis"), "dmp.basis")
    basis.only(("periodic_centres", "periodic_widths", "transient_centres", "transient_widths", "transient_sizes",
                "fading"))
    centres = basis.array("periodic_centres", (None,))
    n = centres.size
    if n < 1:
        raise ValueError("dmp.basis.periodic_centres: expected at least one periodic basis function")
    widths = basis.array("periodic_widths", (n,), positive=True)
    transient_centres = basis.array("transient_centres", (None, 2))
    m = transient_centres.shape[0]
    transient_widths = basis.array("transient_widths", (m,), positive=True)
    sizes = basis.field("transient_sizes")
    if not isinstance(sizes, list) or any(isinstance(k, bool) or not isinstance(k, int) or k < 1 for k in sizes):
        raise ValueError(f"dmp.basis.transient_sizes: expected a list of integers >= 1, got {sizes!r}")
    if sum(sizes) != m:
        raise ValueError(f"dmp.basis.transient_sizes: they add up to {sum(sizes)}, but there are {m} transient "
                         "basis functions (transient_centres, transient_widths)")
    fading = _Reader(basis.field("fading"), "dmp.basis.fading")
    fading.only(("mu1", "mu2", "k", "delta", "floor"))
    mu1, mu2 = fading.number("mu1", positive=True), fading.number("mu2", positive=True)
    if mu2 <= mu1:
        raise ValueError(f"dmp.basis.fading.mu2: must exceed mu1 = {mu1:g}, got {mu2:g}")
    delta = fading.number("delta", positive=True, default=1e-3)
    if delta >= 1.0:
        raise ValueError(f"dmp.basis.fading.delta: expected a value in (0, 1), got {delta:g}")
    floor = fading.number("floor", positive=True, default=NORMALISATION_EPSILON)   # files before the floor: 1e-10
    basis_set = BasisSet(periodic_centres=centres, periodic_widths=widths, transient_centres=transient_centres,
                         transient_widths=transient_widths, transient_sizes=tuple(sizes),
                         fading=Fading(mu1, mu2, fading.integer("k", low=1, default=4), delta, floor))

    weights = top.array("weights", (d, n + m))
    items = top.field("transients")
    if not isinstance(items, list) or len(items) != len(sizes):
        raise ValueError(f"dmp.transients: expected a list of {len(sizes)} (one per entry of transient_sizes), "
                         f"got {items if not isinstance(items, list) else len(items)!r}")
    transients = []
    for k, item in enumerate(items):
        entry = _Reader(item, f"dmp.transients[{k}]")
        entry.only(("phi0", "r0", "length", "entrance_phase", "start", "start_velocity"))
        transients.append(TransientStart(entry.number("phi0"), entry.number("r0", positive=True),
                                         entry.number("length", positive=True), entry.number("entrance_phase"),
                                         entry.array("start", (d,)), entry.array("start_velocity", (d,))))
    ending = _read_stop(top.field("stop"), d) if "stop" in data else None
    sweep = _read_sweep(top.field("sweep"), d) if "sweep" in data else None
    dmp = RhythmicDMP(system, basis_set, weights, transients, anchor, alpha_z, amplitude, ending, sweep)
    return PoseDMP(dmp, _read_reference(top.field("orientation"), d)) if "orientation" in data else dmp


def _read_reference(value: object, d: int) -> np.ndarray:
    """The reference orientation ``[4]`` of a pose DMP of ``d`` dimensions; errors name ``dmp.orientation...``."""
    entry = _Reader(value, "dmp.orientation")
    entry.only(("reference",))
    if d <= ORIENTATION_DIMS:
        raise ValueError(f"dmp.orientation: a pose DMP needs position dimensions and {ORIENTATION_DIMS} tangent "
                         f"dimensions, the file has {d}")
    return check_unit(entry.array("reference", (4,)), "dmp.orientation.reference")


def _read_sweep(value: object, d: int) -> Sweep:
    """The anchor's travel from its plain form; errors name the field ``dmp.sweep...``."""
    entry = _Reader(value, "dmp.sweep")
    entry.only(("times", "points"))
    times = entry.array("times", (None,))
    points = entry.array("points", (max(times.size - 1, 0), d))
    try:
        return Sweep(times, points)
    except ValueError as error:
        raise ValueError(f"dmp.sweep.{error}") from error


def _read_stop(value: object, d: int) -> Ending:
    """The optional ``stop`` field (:meth:`Ending.to_dict`), every field checked like the rest of the file."""
    stop = _Reader(value, "dmp.stop")
    stop.only(("exit_phase", "length", "blend_start", "goal", "centres", "widths", "weights", "fading"))
    exit_phase, length = stop.number("exit_phase"), stop.number("length", positive=True)
    blend_start = stop.number("blend_start")
    if not 0.0 <= blend_start < length:
        raise ValueError(f"dmp.stop.blend_start: expected a value in [0, length = {length:g}), got {blend_start:g}")
    goal = stop.array("goal", (d,))
    centres = stop.array("centres", (None, 2))
    n_stop = centres.shape[0]
    if n_stop < 1:
        raise ValueError("dmp.stop.centres: expected at least one stop basis function")
    widths = stop.array("widths", (n_stop,), positive=True)
    weights = stop.array("weights", (d, n_stop))
    fading = _Reader(stop.field("fading"), "dmp.stop.fading")
    fading.only(("nu1", "nu2", "k", "delta"))
    nu1, nu2 = fading.number("nu1", positive=True), fading.number("nu2", positive=True)
    if nu1 <= nu2:
        raise ValueError(f"dmp.stop.fading.nu1: must exceed nu2 = {nu2:g}, got {nu1:g}")
    delta = fading.number("delta", positive=True)
    if delta >= 1.0:
        raise ValueError(f"dmp.stop.fading.delta: expected a value in (0, 1), got {delta:g}")
    return Ending(exit_phase, length, blend_start, goal, centres, widths, weights,
                  StopFading(nu1, nu2, fading.integer("k", low=1), delta))


def save_dmp(dmp: RhythmicDMP | PoseDMP, path: str | Path) -> None:
    """Write ``dmp`` to ``path`` as JSON."""
    Path(path).write_text(json.dumps(dmp_to_dict(dmp), indent=1))


def load_dmp(path: str | Path) -> RhythmicDMP | PoseDMP:
    """Read a DMP written by :func:`save_dmp` (a :class:`~rdmp_gym.dmp.pose.PoseDMP` for a pose); a broken file is a
    ``ValueError`` naming it and the field."""
    path = Path(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as error:
        raise ValueError(f"path: {path}: not a JSON DMP file ({error})") from error
    try:
        return dmp_from_dict(data)
    except ValueError as error:
        raise ValueError(f"path: {path}: {error}") from error
