"""Realistic pose recordings: :func:`rdmp_gym.synthetic.demonstrations.realistic_recording`'s positions with a tool
orientation.

The tool turns from its start orientation to its working orientation during the approach (optionally with an
extra yaw ``turn`` about the vertical), tilts and rolls with the rhythm (leaning with the stroke, ``tilt`` at full
size), drifts slowly while it works, turns to a rest orientation as the hand leaves, and the recorder adds
coloured angular noise and writes ``q`` or ``-q`` at random. The positions are those of
``realistic_recording(kind, rng=rng)``, bit for bit: the orientation draws from ``rng`` after them.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..dmp import quaternion
from ..recordings.pose_io import write_pose_csv
from ..validation import as_finite_array
from .demonstrations import RECORDING_KINDS, RecordingTruth, coloured_noise, realistic_recording

__all__ = ["PoseRecording", "realistic_pose_recording"]

_TOOL_DOWN = np.array([0.0, 1.0, 0.0, 0.0])     # the tool points down: half a turn about x


@dataclass(frozen=True, eq=False)
class PoseRecording:
    """Positions ``Y [L, 3]`` (m) and unit quaternions ``Q [L, 4]`` (w, x, y, z; either sign) at uneven stamps
    ``t [L]`` (s); ``truth`` of the positions and the noise-free orientation ``clean_orientation [L, 4]``."""

    t: np.ndarray
    Y: np.ndarray
    Q: np.ndarray
    name: str
    truth: RecordingTruth
    clean_orientation: np.ndarray

    def to_csv(self, path: str | Path, time_column: str = "t") -> None:
        """Write the samples as CSV: ``time_column, x, y, z, qw, qx, qy, qz`` (17 significant digits)."""
        write_pose_csv(path, self.t, self.Y, self.Q, time_column)


def _smoothstep(u: np.ndarray) -> np.ndarray:
    """0 before 0, 1 after 1, a quintic with zero slope and curvature at both ends between."""
    u = np.clip(u, 0.0, 1.0)
    return u**3 * (10.0 - 15.0 * u + 6.0 * u**2)


def realistic_pose_recording(kind: str = "wiping", *, rng: np.random.Generator, tilt: float = 8.0,
                             turn: float = 0.0, noise: float = 0.05, sign_flips: bool = True,
                             **position_keywords) -> PoseRecording:
    """A pose recording of a person's rhythmic demonstration (see the module docstring).

    Args:
        kind, rng, position_keywords: as in :func:`~rdmp_gym.synthetic.demonstrations.realistic_recording` (the
            positions).
        tilt: the tool's tilt with the rhythm at full size (deg); it rolls by a third of that at twice the rate.
        turn: an extra yaw about the vertical during the approach (deg; 180 turns the tool half round).
        noise: standard deviation of the angular noise (deg; coloured, correlation time 50 ms).
        sign_flips: write ``-q`` for a random half of the samples (recorders do not keep ``w >= 0``).
    """
    recording = realistic_recording(kind, rng=rng, **position_keywords)
    tilt, turn, noise = (np.radians(float(as_finite_array(value, name, ndim=0)))
                         for value, name in ((tilt, "tilt"), (turn, "turn"), (noise, "noise")))
    truth, t = recording.truth, recording.t
    radii = np.array(RECORDING_KINDS[kind].radii)
    stroke = (truth.clean - truth.working_point)[:, :2] / radii                 # [L, 2], about unit at full size
    start, work, drift, goal = (rng.normal(0.0, scale, 3) for scale in (0.25, 0.08, 0.04, 0.2))
    approach = _smoothstep((t - truth.onset) / (truth.rhythm_start - truth.onset))[:, None]
    working = _smoothstep((t - truth.rhythm_start) / (truth.rhythm_end - truth.rhythm_start))[:, None]
    leaving = _smoothstep((t - truth.rhythm_end) / (truth.rest_time - truth.rhythm_end))[:, None]
    rhythm = np.column_stack([tilt * stroke[:, 1], -tilt * stroke[:, 0], tilt / 3.0 * stroke[:, 0] * stroke[:, 1]])
    body = start + approach * (work - start) + working * drift + leaving * (goal - work - drift) + rhythm
    yaw = quaternion.exp_map(np.outer(turn * approach[:, 0], [0.0, 0.0, 1.0]))
    clean = quaternion.multiply(yaw, quaternion.multiply(_TOOL_DOWN, quaternion.exp_map(body)))
    Q = quaternion.multiply(clean, quaternion.exp_map(noise * coloured_noise(t, rng)))
    if sign_flips:
        Q = Q * np.where(rng.random(t.size) < 0.5, -1.0, 1.0)[:, None]
    return PoseRecording(t=t, Y=recording.Y, Q=Q, name=f"{kind} pose recording", truth=truth,
                         clean_orientation=clean)
