"""The episode context of the wiping task: table pose, dirt patch, sponge start, obstacle.

The context is the observation of the episodic env: a float32 vector ``[13]``

    0        table_height       offset of the table top from its nominal height (m)
    1, 2     table_tilt         table roll about the table frame's x axis, pitch about its y axis (rad)
    3, 4     patch_centre       centre of the dirty patch in the nominal table frame (m)
    5, 6     patch_size         side lengths of the dirty patch (m)
    7, 8, 9  sponge_start       start of the sponge face centre in the nominal table frame (m; z above the surface)
    10       obstacle           1 if a cup stands on the table in this episode, else 0
    11, 12   obstacle_position  the cup's centre on the table (table frame, m); (0, 0) when there is none

Each field has a *sampling* range (what ``reset`` draws from, well inside the reach) and wider
*bounds* (the observation space; what ``reset(options=...)`` accepts). Whatever is drawn or given,
the whole dirt patch lies on the table top, and a cup stands on the table, off the patch; a context
that breaks either raises ``ValueError``. A cup given in the options is checked like a drawn one: it also keeps
``patch_clearance`` (plus its radius) from the sponge start, whose pad would otherwise start on it; ``obstacle``
is 0 or 1, and ``obstacle_position`` comes with ``obstacle = 1`` (or in the whole ``context``). The cup keeps
``patch_clearance`` from the patch (1 cm in ``ArmarWipe-v1``; in ``ArmarWipe-v2`` the pad's half-diagonal plus
1 cm, so the pad can wipe the patch edge).

The cup is not drawn uniformly: with probability ``obstacle_probability`` it stands in the approach
corridor, on the line from the sponge start (projected on the table) to the patch centre, 35-60 % of
the way, within 1 cm of the line, where the imitation's approach comes down on it. ``ArmarWipe-v2`` keeps
the clearance from the patch and from the sponge start (whose pad would otherwise start on the cup): the cup
stands anywhere on the corridor that allows it, or else 0-4 cm beyond the clearance on the patch's -y side
(away from the fingers and the forearm), where the travelling pattern must not reach it. A draw that would
put it on the patch or off the table leaves the context without a cup.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

__all__ = ["CONTEXT_FIELDS", "CONTEXT_KINDS", "Context", "ContextSpec"]

#: name -> (first index, length) in the context vector
CONTEXT_FIELDS: dict[str, tuple[int, int]] = {
    "table_height": (0, 1),
    "table_tilt": (1, 2),
    "patch_centre": (3, 2),
    "patch_size": (5, 2),
    "sponge_start": (7, 3),
    "obstacle": (10, 1),
    "obstacle_position": (11, 2),
}
_ALIASES = {"patch_center": "patch_centre"}
SIZE = 13
_DRAWN = 10          # fields 0..9 are drawn uniformly; the obstacle fields are placed

_SAMPLE_LOW = np.array([-0.02, -0.05, -0.05, -0.02, -0.04, 0.10, 0.10, -0.10, 0.20, 0.10, 0.0, 0.0, 0.0])
_SAMPLE_HIGH = np.array([0.02, 0.05, 0.05, 0.03, 0.04, 0.22, 0.22, 0.00, 0.28, 0.14, 1.0, 0.0, 0.0])
_BOUND_LOW = np.array([-0.06, -0.15, -0.15, -0.15, -0.20, 0.02, 0.02, -0.30, -0.30, 0.0, 0.0, -0.30, -0.45])
_BOUND_HIGH = np.array([0.06, 0.15, 0.15, 0.15, 0.20, 0.30, 0.30, 0.20, 0.30, 0.25, 1.0, 0.40, 0.45])

#: Default clearance (m) kept between the cup's rim and the dirty patch (``ArmarWipe-v1``'s).
PATCH_CLEARANCE = 0.01


@dataclass(frozen=True)
class Context:
    """One episode's context (float64 fields; see the module docstring)."""

    table_height: float
    table_tilt: np.ndarray
    patch_centre: np.ndarray
    patch_size: np.ndarray
    sponge_start: np.ndarray
    obstacle: bool = False
    obstacle_position: np.ndarray = field(default_factory=lambda: np.zeros(2))

    def vector(self) -> np.ndarray:
        """The context as a float64 vector ``[13]``."""
        return np.concatenate([[self.table_height], self.table_tilt, self.patch_centre, self.patch_size,
                               self.sponge_start, [float(self.obstacle)],
                               self.obstacle_position if self.obstacle else np.zeros(2)])

    @classmethod
    def from_vector(cls, v: np.ndarray) -> Context:
        """Inverse of :meth:`vector`."""
        v = np.asarray(v, dtype=np.float64)
        present = bool(v[10] >= 0.5)
        return cls(float(v[0]), v[1:3].copy(), v[3:5].copy(), v[5:7].copy(), v[7:10].copy(), present,
                   v[11:13].copy() if present else np.zeros(2))


#: the kinds of wiping context, in the order of :meth:`ContextSpec.kind`'s priority
CONTEXT_KINDS = ("cup on the approach", "cup beside the patch", "largest patch", "no cup")
#: a cup within this distance (m) of the line from the sponge start to the patch centre, between them, stands on
#: the approach (the corridor's cups stand within 1 cm of it)
APPROACH_LANE = 0.015
#: the largest patches: an area in the top quarter of the drawable areas' span
LARGE_PATCH_SHARE = 0.75


class ContextSpec:
    """Sampling ranges, bounds and consistency rules of the context.

    Args:
        ranges: optional ``{field: (low, high)}`` overrides of the sampling ranges of fields 0-9 (each a
            number or the field's length of numbers); they must lie within the bounds.
        table_extent: the table top in the table frame, (x_low, x_high, y_low, y_high) (m).
        obstacle: whether contexts may have a cup at all.
        obstacle_probability: share of drawn contexts that get a cup (when it fits).
        obstacle_radius: the cup's radius (m).
        patch_clearance: the least distance (m) between the cup's rim and the dirty patch.
        near_patch: place the cup anywhere on the corridor that keeps ``patch_clearance`` from both the patch and
            the sponge start (instead of 35-60 % of the way, which ``ArmarWipe-v2``'s clearance leaves too little
            room for), or, where the corridor is too short, 0-4 cm beyond the clearance on the patch's -y side.
    """

    def __init__(self, ranges: Mapping[str, tuple] | None = None,
                 table_extent: tuple[float, float, float, float] = (-0.14, 0.36, -0.45, 0.45),
                 obstacle: bool = True, obstacle_probability: float = 0.75, obstacle_radius: float = 0.035,
                 patch_clearance: float = PATCH_CLEARANCE, near_patch: bool = False):
        self.low = _SAMPLE_LOW.copy()
        self.high = _SAMPLE_HIGH.copy()
        self.bound_low = _BOUND_LOW.copy()
        self.bound_high = _BOUND_HIGH.copy()
        self.table_extent = tuple(float(x) for x in table_extent)
        self.obstacle = bool(obstacle)
        if not (0.0 <= obstacle_probability <= 1.0):
            raise ValueError(f"obstacle_probability: expected a number in [0, 1], got {obstacle_probability!r}")
        self.obstacle_probability = float(obstacle_probability)
        self.obstacle_radius = float(obstacle_radius)
        if not (np.isfinite(patch_clearance) and patch_clearance >= 0.0):
            raise ValueError(f"patch_clearance: expected a number >= 0 (m), got {patch_clearance!r}")
        self.patch_clearance = float(patch_clearance)
        self.near_patch = bool(near_patch)
        for key, value in (ranges or {}).items():
            start, length = self._field(key, "context_ranges")
            if start >= _DRAWN:
                raise ValueError(f"context_ranges: {key} is placed, not drawn from a range; use obstacle=False "
                                 "or obstacle_probability instead")
            try:
                low, high = (np.broadcast_to(np.asarray(x, dtype=np.float64), (length,)) for x in value)
            except (TypeError, ValueError) as error:
                raise ValueError(f"context_ranges: {key} must be (low, high) with {length} number(s) each") from error
            part = slice(start, start + length)
            if (not (np.all(np.isfinite(low)) and np.all(np.isfinite(high))) or np.any(low > high)
                    or np.any(low < self.bound_low[part]) or np.any(high > self.bound_high[part])):
                raise ValueError(f"context_ranges: {key} = ({low}, {high}) must satisfy low <= high within "
                                 f"[{self.bound_low[part]}, {self.bound_high[part]}]")
            self.low[part], self.high[part] = low, high
        # every drawable patch must lie on the table
        x_lo, x_hi, y_lo, y_hi = self.table_extent
        half = self.high[5:7] / 2
        if (self.low[3] - half[0] < x_lo - 1e-9 or self.high[3] + half[0] > x_hi + 1e-9
                or self.low[4] - half[1] < y_lo - 1e-9 or self.high[4] + half[1] > y_hi + 1e-9):
            raise ValueError("context_ranges: patch_centre and patch_size ranges allow patches beyond the table "
                             f"top {self.table_extent} (table frame, m)")

    @staticmethod
    def _field(key: str, argument: str) -> tuple[int, int]:
        name = _ALIASES.get(key, key)
        if name not in CONTEXT_FIELDS:
            raise ValueError(f"{argument}: unknown context field {key!r}; expected one of "
                             f"{[*CONTEXT_FIELDS, 'context']}")
        return CONTEXT_FIELDS[name]

    def sample(self, rng: np.random.Generator, options: Mapping | None = None) -> Context:
        """Draw a context from ``rng``; ``options`` fixes fields (or ``context``: the whole vector).

        Raises ValueError for a patch beyond the table top, a cup off the table, on the patch or (given) on the
        sponge start, an ``obstacle`` other than 0 or 1, or an ``obstacle_position`` without ``obstacle = 1``."""
        vector = np.r_[rng.uniform(self.low[:_DRAWN], self.high[:_DRAWN]), 0.0, 0.0, 0.0]
        draw = rng.uniform(size=4)                      # presence, position along and across the corridor
        given: set[str] = set()
        named: set[str] = set()                         # fields given by their own name (not in ``context``)
        for key, value in (options or {}).items():
            if key == "context":
                start, length = 0, SIZE
                given |= {"obstacle", "obstacle_position"}
            else:
                start, length = self._field(key, "options")
                given.add(_ALIASES.get(key, key))
                named.add(_ALIASES.get(key, key))
            try:
                array = np.asarray(value, dtype=np.float64).reshape(-1)
            except (TypeError, ValueError) as error:
                raise ValueError(f"options: {key} must be numeric") from error
            if array.size != length:
                raise ValueError(f"options: {key} expects {length} number(s), got {array.size}")
            part = slice(start, start + length)
            if not np.all(np.isfinite(array)):
                raise ValueError(f"options: {key} contains NaN or infinite values")
            if np.any(array < self.bound_low[part]) or np.any(array > self.bound_high[part]):
                raise ValueError(f"options: {key} = {array} lies outside the bounds "
                                 f"[{self.bound_low[part]}, {self.bound_high[part]}]")
            presence = array[10 - start] if start <= 10 < start + length else 0.0
            if presence not in (0.0, 1.0):
                raise ValueError(f"options: obstacle expects 0 (no cup) or 1 (a cup), got {presence:g}")
            vector[part] = array
        if "obstacle_position" in named and "obstacle" not in given:
            raise ValueError("options: obstacle_position is given without obstacle; give obstacle = 1 with it "
                             "(or the whole context)")
        if "obstacle_position" in named and vector[10] == 0.0:
            raise ValueError("options: obstacle_position is given with obstacle = 0 (no cup); give obstacle = 1 "
                             "or leave obstacle_position out")
        context = Context.from_vector(vector)
        self._check_patch(context)
        present = context.obstacle if "obstacle" in given else draw[0] < self.obstacle_probability
        if present and not self.obstacle:
            if "obstacle" in given:
                raise ValueError("options: obstacle = 1 but the env was made with obstacle=False")
            present = False
        position = context.obstacle_position
        if present and "obstacle_position" not in given:
            position = self._corridor_point(context, draw[1:])
            if position is None:
                if "obstacle" in given:
                    raise ValueError("options: obstacle = 1 but no cup fits in this context's approach corridor; "
                                     "give obstacle_position")
                present = False
        context = Context(context.table_height, context.table_tilt, context.patch_centre, context.patch_size,
                          context.sponge_start, bool(present), position if present else np.zeros(2))
        if present and self._misplaced(context, position):
            raise ValueError(f"options: obstacle_position {position} puts the cup (radius {self.obstacle_radius} m) "
                             f"off the table top {self.table_extent} or on the dirt patch")
        if present and "obstacle_position" in given:
            self._check_start(context, position)
        return context

    def kind(self, context: Context) -> str:
        """The kind of ``context`` (one of :data:`CONTEXT_KINDS`): a cup on the approach (within
        :data:`APPROACH_LANE` of the line from the sponge start to the patch centre, between them), a cup elsewhere
        (beside the patch), no cup on one of the largest patches, or no cup."""
        if context.obstacle:
            start, centre = context.sponge_start[:2], context.patch_centre
            line = centre - start
            along = float(np.dot(context.obstacle_position - start, line) / max(float(np.dot(line, line)), 1e-12))
            across = float(np.linalg.norm(context.obstacle_position - (start + along * line)))
            return CONTEXT_KINDS[0] if 0.0 < along < 1.0 and across <= APPROACH_LANE else CONTEXT_KINDS[1]
        low, high = np.prod(self.low[5:7]), np.prod(self.high[5:7])
        large = np.prod(context.patch_size) >= low + LARGE_PATCH_SHARE * (high - low)
        return CONTEXT_KINDS[2] if large else CONTEXT_KINDS[3]

    def _check_start(self, context: Context, xy: np.ndarray) -> None:
        """A given cup keeps what a drawn one keeps from the sponge start (projected on the table): its radius plus
        ``patch_clearance`` (1e-6 m of slack for a context read back from the float32 observation)."""
        reach = self.obstacle_radius + self.patch_clearance
        gap = float(np.linalg.norm(xy - context.sponge_start[:2]))
        if gap < reach - 1e-6:
            raise ValueError(f"options: obstacle_position {xy} puts the cup {gap:.3f} m from the sponge start "
                             f"{context.sponge_start[:2]} (table frame), where the pad starts on it; expected at "
                             f"least {reach:.3f} m (the cup's radius + patch_clearance)")

    def _check_patch(self, context: Context) -> None:
        x_lo, x_hi, y_lo, y_hi = self.table_extent
        low = context.patch_centre - context.patch_size / 2
        high = context.patch_centre + context.patch_size / 2
        if low[0] < x_lo - 1e-9 or high[0] > x_hi + 1e-9 or low[1] < y_lo - 1e-9 or high[1] > y_hi + 1e-9:
            raise ValueError(f"options: the dirt patch [{low}, {high}] (table frame, m) extends beyond the table "
                             f"top x in [{x_lo}, {x_hi}], y in [{y_lo}, {y_hi}]; dirt lives on the table only")

    def _misplaced(self, context: Context, xy: np.ndarray) -> bool:
        x_lo, x_hi, y_lo, y_hi = self.table_extent
        r = self.obstacle_radius
        off_table = xy[0] - r < x_lo or xy[0] + r > x_hi or xy[1] - r < y_lo or xy[1] + r > y_hi
        gap = np.maximum(np.abs(xy - context.patch_centre) - context.patch_size / 2, 0.0)
        on_patch = bool(np.hypot(*gap) < r + self.patch_clearance)
        return off_table or on_patch

    def _beside_patch(self, context: Context, draw: np.ndarray, reach: float) -> np.ndarray | None:
        """A cup 0-4 cm beyond the clearance from the patch, ``reach`` from the sponge start (None where that is off
        the table or too close to the start), on the patch's -y side (table frame, within 45°): the hand's fingers
        reach about 13 cm beyond the pad along +x at the cup's height and the forearm lies towards -x and +y, so
        a cup there is hit by the arm however the pad wipes."""
        angle = -0.5 * np.pi + 0.5 * np.pi * (draw[1] - 0.5)      # the -y side, +-45°: away from the forearm (-x, +y)
        direction = np.array([np.cos(angle), np.sin(angle)])      # and from the fingers (+x), see the docstring
        wanted = self.obstacle_radius + self.patch_clearance + 0.04 * draw[0]
        for distance in np.arange(0.0, 0.6, 0.002):
            xy = context.patch_centre + distance * direction
            gap = np.maximum(np.abs(xy - context.patch_centre) - context.patch_size / 2, 0.0)
            if np.hypot(*gap) >= wanted:
                far = np.linalg.norm(xy - context.sponge_start[:2]) >= reach
                return xy if far and not self._misplaced(context, xy) else None
        return None

    def _corridor_point(self, context: Context, draw: np.ndarray) -> np.ndarray | None:
        start, centre = context.sponge_start[:2], context.patch_centre
        line = centre - start
        length = float(np.linalg.norm(line))
        if length < 1e-6:
            return None
        along = line / length
        across = np.array([-along[1], along[0]])
        side = (draw[1] - 0.5) * 0.02 * across
        if self.near_patch:        # anywhere on the corridor that keeps the clearance from the patch and the start
            fractions = np.arange(0.0, 1.0, 0.005)
            reach = self.obstacle_radius + self.patch_clearance
            clear = [f for f in fractions if not self._misplaced(context, start + f * line + side)
                     and np.linalg.norm(f * line + side) >= reach]
            if not clear:
                return self._beside_patch(context, draw, reach)
            fraction = clear[0] + draw[0] * (clear[-1] - clear[0])
        else:
            fraction = 0.35 + 0.25 * draw[0]
        xy = start + fraction * line + side
        if self._misplaced(context, xy):
            return None
        return xy
