"""The ``sweep`` action of ``ArmarWipe-v2``: the anchor travels over a rectangle so that the pattern covers a
patch larger than one loop.

A loop in place covers a disc about the loop's size plus the pad's; a larger patch needs the circling hand
to move across it, as people wipe a table. The DMP can do that: its anchor follows a minimum-jerk path through
via points (:class:`rdmp_gym.Sweep`, the discrete part of a discrete + rhythmic movement) and the rhythmic
pattern is carried along it rigidly.

The path is a fixed covering figure scaled per table axis: from the patch centre (where the approach lands,
at rest) out to ``(x, 0)``, once around the ellipse with half-axes ``x`` and ``y`` (via points every 45°), and
home to the centre, where it rests until the episode ends. The via points are evenly spaced in time from the
end of the transient to half a second before the end of the episode. The loop circling on this path covers a
ring of the ellipse's size plus its own and the pad's; its passes through the centre cover the middle.
The offsets are linear in the half-extents ``x`` and ``y``, so the two numbers are two action dimensions,
``sweep_x`` and ``sweep_y`` (``x = scale * a``, 6 cm at ``a = +1`` by default), that move the DMP's own
``sweep`` parameters (the via points) along a fixed direction each: "cover a patch this much larger than the
loop" is two numbers, and ``a = 0`` leaves the anchor at rest at the centre (the imitation). A negative
value mirrors the figure (the ellipse run the other way round).
"""

from __future__ import annotations

import numpy as np

from rdmp_gym import RhythmicDMP, Sweep

__all__ = ["COVERING_FIGURE", "covering_sweep", "sweep_directions"]

_ANGLES = np.deg2rad(np.arange(0.0, 361.0, 45.0))
#: The covering figure's via points in units of the half-extents (x, y), after the start at the centre: out along
#: x, once around the ellipse in 45° steps, back to the centre. The minimum-jerk path through them stays within
#: the ellipse's box to 0.3 % (a rectangle's corners made it overshoot by 57 %).
COVERING_FIGURE = np.r_[[[0.5, 0.0]], np.c_[np.cos(_ANGLES), np.sin(_ANGLES)], [[0.5, 0.0], [0.0, 0.0]]]


def covering_sweep(start: float, end: float, n_dims: int) -> Sweep:
    """The sweep of the covering figure (all offsets 0: at rest) with its via points evenly spaced in
    ``[start, end]`` (DMP time, s)."""
    if not 0.0 <= start < end:
        raise ValueError(f"start, end: expected 0 <= start < end, got {start!r}, {end!r}")
    count = len(COVERING_FIGURE)
    return Sweep(np.linspace(start, end, count + 1), np.zeros((count, n_dims)))


def sweep_directions(dmp: RhythmicDMP, groups: tuple[str, ...]) -> dict[str, np.ndarray]:
    """``{"sweep_x": delta [P], "sweep_y": delta [P]}``: the change of the parameters of ``groups`` (which
    must hold ``"sweep"``) that moves the via points by the covering figure with a half-extent of 1 m along the
    table's x (y) axis."""
    if dmp.sweep is None or dmp.sweep.n_points != len(COVERING_FIGURE):
        raise ValueError("dmp: expected a DMP with the covering sweep (covering_sweep)")
    part = dmp.param_slices(groups).get("sweep")
    if part is None:
        raise ValueError(f"groups: expected the group 'sweep' among {groups}")
    size = dmp.layout.size(groups)
    directions = {}
    for axis, name in enumerate(("sweep_x", "sweep_y")):
        points = np.zeros((len(COVERING_FIGURE), dmp.n_dims))
        points[:, axis] = COVERING_FIGURE[:, axis]
        delta = np.zeros(size)
        delta[part] = points.ravel()
        directions[name] = delta
    return directions
