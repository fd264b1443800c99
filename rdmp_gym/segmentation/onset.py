"""Where a person's rhythm starts and stops as people mark it: the hand enters and leaves the region that the
full-size rhythm sweeps.

The full-size rhythm (:func:`~rdmp_gym.segmentation.segment_rhythm`'s ``rhythm_start`` to ``rhythm_end``) starts
after the growing first strokes, about a period after a person would say the work begins (the contact with the
surface, the first stroke). The hand is *in the rhythm* while it stays within :data:`ENTER_SHARE` of the rhythm's
size (the RMS distance of its samples from their mean) of some sample of the full-size rhythm: the approach ends
where it enters that region for the last time before the full-size rhythm, the departure begins where it first
leaves it after. The growing first strokes lie inside the region; an approach from above a surface does not, until
it touches down.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

__all__ = ["ENTER_SHARE", "rhythm_bounds", "sweep_size"]

ENTER_SHARE = 0.3
"""The hand is in the rhythm within this share of the rhythm's size of one of its samples."""


def rhythm_bounds(Y: np.ndarray, first: int, last: int, share: float = ENTER_SHARE) -> tuple[int, int]:
    """``(onset, stop)``: the indices where the hand enters (last entry before ``first``) and leaves (first exit
    after ``last``) the region swept by the full-size rhythm ``Y[first:last + 1]`` (``Y [L, d]``); ``0`` and
    ``L - 1`` when it is in the region from the first or to the last sample."""
    rhythm = Y[first:last + 1]
    size = sweep_size(rhythm)
    tree = cKDTree(rhythm)
    outside_before = np.flatnonzero(tree.query(Y[:first])[0] > share * size)
    outside_after = np.flatnonzero(tree.query(Y[last + 1:])[0] > share * size)
    onset = int(outside_before[-1]) + 1 if outside_before.size else 0
    stop = last + int(outside_after[0]) if outside_after.size else Y.shape[0] - 1
    return onset, stop


def sweep_size(points: np.ndarray) -> float:
    """The size of the motion ``points [N, d]``: the RMS distance of its samples from their mean."""
    return float(np.sqrt(np.mean(np.sum((points - points.mean(axis=0)) ** 2, axis=1))))
