"""Save and load DMPs as JSON (lossless: floats are written with ``repr`` precision).

Format ``rdmp-gym/rhythmic-dmp``, version 1. Top-level keys:

* ``format`` (str), ``version`` (int)
* ``canonical``: ``period, mu, eta, alpha, beta, tempo``
* ``transformation``: ``alpha_z`` (``beta_z = alpha_z / 4``)
* ``anchor``: ``[d]``
* ``amplitude``: ``[d]`` (factors that scale the movement about the anchor)
* ``basis``: ``periodic_centres [N]``, ``periodic_widths [N]``, ``transient_centres [M, 2]``,
  ``transient_widths [M]``, ``transient_sizes [K]``, ``fading {mu1, mu2, k, delta}``
* ``weights``: ``[d, D]`` (periodic columns first, then each transient's)
* ``transients``: K objects ``{phi0, r0, length, entrance_phase, start [d], start_velocity [d]}``
* ``stop`` (optional, absent for a DMP without an end of the movement): ``{exit_phase, length, blend_start,
  goal [d], centres [S, 2], widths [S], weights [d, S], fading {nu1, nu2, k, delta}}``
"""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path

import numpy as np

from .basis import BasisSet, Fading
from .canonical import CanonicalSystem
from .dmp import RhythmicDMP, TransientStart
from .stopping import Ending

__all__ = ["FORMAT", "VERSION", "dmp_from_dict", "dmp_to_dict", "load_dmp", "save_dmp"]

FORMAT = "rdmp-gym/rhythmic-dmp"
VERSION = 1


def dmp_to_dict(dmp: RhythmicDMP) -> dict:
    """A JSON-ready dictionary of every number that defines ``dmp``."""
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
    return data


def dmp_from_dict(data: dict) -> RhythmicDMP:
    """Rebuild a DMP from :func:`dmp_to_dict`'s output; raises ``ValueError`` on another format or version."""
    if data.get("format") != FORMAT:
        raise ValueError(f"path: not an rdmp-gym DMP file (format {data.get('format')!r})")
    if data.get("version") != VERSION:
        raise ValueError(f"path: unsupported format version {data.get('version')!r}; this library reads {VERSION}")
    try:
        basis = data["basis"]
        basis_set = BasisSet(
            periodic_centres=np.array(basis["periodic_centres"], dtype=float),
            periodic_widths=np.array(basis["periodic_widths"], dtype=float),
            transient_centres=np.array(basis["transient_centres"], dtype=float).reshape(-1, 2),
            transient_widths=np.array(basis["transient_widths"], dtype=float),
            transient_sizes=tuple(int(m) for m in basis["transient_sizes"]),
            fading=Fading(**basis["fading"]))
        transients = [TransientStart(float(s["phi0"]), float(s["r0"]), float(s["length"]),
                                     float(s["entrance_phase"]), np.array(s["start"], dtype=float),
                                     np.array(s["start_velocity"], dtype=float)) for s in data["transients"]]
        return RhythmicDMP(CanonicalSystem(**data["canonical"]), basis_set, np.array(data["weights"], dtype=float),
                           transients, np.array(data["anchor"], dtype=float), data["transformation"]["alpha_z"],
                           np.array(data["amplitude"], dtype=float),
                           Ending.from_dict(data["stop"]) if "stop" in data else None)
    except KeyError as error:
        raise ValueError(f"path: DMP file is missing the field {error.args[0]!r}") from error


def save_dmp(dmp: RhythmicDMP, path: str | Path) -> None:
    """Write ``dmp`` to ``path`` as JSON."""
    Path(path).write_text(json.dumps(dmp_to_dict(dmp), indent=1))


def load_dmp(path: str | Path) -> RhythmicDMP:
    """Read a DMP written by :func:`save_dmp`."""
    return dmp_from_dict(json.loads(Path(path).read_text()))
