"""Where a person's rhythm starts and stops as people mark it: the hand is on the working surface and strokes along it.

The full-size rhythm (:func:`~rdmp_gym.signals.segmentation.segment_rhythm`'s ``rhythm_start`` to ``rhythm_end``) starts
after the first strokes, about a period after a person would say the work begins. The working surface is the plane
of the full-size rhythm: its normal the direction in which its positions vary least, through their mean. The hand
is *on* it within :data:`CONTACT_SHARE` of the rhythm's size (the RMS distance of its samples from their mean), or
three times the spread of the rhythm's own distances from the plane where that is more; brief departures, shorter
than :data:`GAP_PERIODS` periods, do not count. It *strokes* while its speed along the plane (averaged over a
period) is at least :data:`SPEED_SHARE` of the rhythm's typical one and its net motion along the plane over that
period at most :data:`DRIFT_SHARE` of it (back and forth, not an approach). The onset is the first stroke after
the hand comes onto the surface for the last time before the full-size rhythm (waiting at the stroke line is no
stroke; larger first strokes on the same surface are); the stop is the last stroke before it leaves the surface.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import uniform_filter1d

from rdmp_gym.signals.filters import runs

__all__ = ["CONTACT_SHARE", "DRIFT_SHARE", "GAP_PERIODS", "SPEED_SHARE", "rhythm_bounds", "sweep_size"]

CONTACT_SHARE = 0.5
"""The hand is on the surface within this share of the rhythm's size of the rhythm's plane."""
GAP_PERIODS = 1.0
"""Departures from the surface shorter than this many periods do not count."""
SPEED_SHARE = 0.5
"""The hand strokes at this share of the rhythm's typical speed along the plane or more ..."""
DRIFT_SHARE = 0.8
"""... and its net motion along the plane over a period is at most this share of that speed."""


def rhythm_bounds(Y: np.ndarray, first: int, last: int, period: float, dt: float) -> tuple[int, int]:
    """``(onset, stop)``: the indices of the first stroke on the surface before ``first`` and the last one after
    ``last`` (the full-size rhythm ``Y[first:last + 1]``, ``Y [L, d]``, ``period`` and ``dt`` in s; see the
    module docstring); never later than ``first`` or earlier than ``last``."""
    rhythm = Y[first:last + 1]
    mean = rhythm.mean(axis=0)
    normal = np.linalg.svd(rhythm - mean, full_matrices=False)[2][-1]
    height = (Y - mean) @ normal
    tolerance = max(CONTACT_SHARE * sweep_size(rhythm), 3.0 * float(np.std(height[first:last + 1])))
    on = _bridged(np.abs(height) <= tolerance, round(GAP_PERIODS * period / dt))
    stroking = _stroking(Y, normal, first, last, max(1, round(period / dt)), dt)
    off_before, off_after = np.flatnonzero(~on[:first]), np.flatnonzero(~on[last + 1:])
    down = int(off_before[-1]) + 1 if off_before.size else 0
    up = last + int(off_after[0]) if off_after.size else Y.shape[0] - 1
    strokes_before, strokes_after = np.flatnonzero(stroking[down:first]), np.flatnonzero(stroking[last + 1:up + 1])
    onset = down + int(strokes_before[0]) if strokes_before.size else first
    stop = last + 1 + int(strokes_after[-1]) if strokes_after.size else last
    return onset, stop


def _stroking(Y: np.ndarray, normal: np.ndarray, first: int, last: int, window: int, dt: float) -> np.ndarray:
    """``[L]`` whether the hand strokes along the plane of ``normal [d]`` (averages over ``window`` samples)."""
    velocity = np.gradient(Y, dt, axis=0)
    along = velocity - np.outer(velocity @ normal, normal)
    speed = uniform_filter1d(np.linalg.norm(along, axis=1), window, mode="nearest")
    drift = np.linalg.norm(uniform_filter1d(along, window, axis=0, mode="nearest"), axis=1)
    return (speed >= SPEED_SHARE * float(np.median(speed[first:last + 1]))) & (drift <= DRIFT_SHARE * speed)


def _bridged(mask: np.ndarray, gap: int) -> np.ndarray:
    """``mask [L]`` with its runs of False shorter than ``gap`` samples between two runs of True set True."""
    out = mask.copy()
    for start, stop in zip(*runs(~mask), strict=True):
        if 0 < start and stop < mask.size and stop - start < gap:
            out[start:stop] = True
    return out


def sweep_size(points: np.ndarray) -> float:
    """The size of the motion ``points [N, d]``: the RMS distance of its samples from their mean."""
    return float(np.sqrt(np.mean(np.sum((points - points.mean(axis=0)) ** 2, axis=1))))
