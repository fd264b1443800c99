"""The episode context of the wiping task: table pose, dirt patch, sponge start.

The context is the observation of the episodic env: a float32 vector ``[10]``

    0 table_height   offset of the table top from its nominal height (m)
    1 tilt_x         table roll about the table frame's x axis (rad)
    2 tilt_y         table pitch about the table frame's y axis (rad)
    3, 4 patch_centre  centre of the dirty patch in the nominal table frame (m)
    5, 6 patch_size    side lengths of the dirty patch (m)
    7, 8, 9 sponge_start  start of the sponge face centre in the nominal table frame (m; z above the surface)

Each field has a *sampling* range (what ``reset`` draws from, small and well inside the reach) and
wider *bounds* (the observation space; what ``reset(options=...)`` accepts).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

__all__ = ["CONTEXT_FIELDS", "Context", "ContextSpec"]

#: name -> (first index, length) in the context vector
CONTEXT_FIELDS: dict[str, tuple[int, int]] = {
    "table_height": (0, 1),
    "table_tilt": (1, 2),
    "patch_centre": (3, 2),
    "patch_size": (5, 2),
    "sponge_start": (7, 3),
}
_ALIASES = {"patch_center": "patch_centre"}
SIZE = 10

_SAMPLE_LOW = np.array([-0.02, -0.05, -0.05, -0.03, -0.04, 0.10, 0.10, -0.12, 0.04, 0.06])
_SAMPLE_HIGH = np.array([0.02, 0.05, 0.05, 0.03, 0.04, 0.22, 0.22, -0.02, 0.16, 0.10])
_BOUND_LOW = np.array([-0.06, -0.15, -0.15, -0.15, -0.20, 0.02, 0.02, -0.30, -0.30, 0.0])
_BOUND_HIGH = np.array([0.06, 0.15, 0.15, 0.15, 0.20, 0.30, 0.30, 0.20, 0.30, 0.25])


@dataclass(frozen=True)
class Context:
    """One episode's context (float64 fields; see the module docstring)."""

    table_height: float
    table_tilt: np.ndarray
    patch_centre: np.ndarray
    patch_size: np.ndarray
    sponge_start: np.ndarray

    def vector(self) -> np.ndarray:
        """The context as a float64 vector ``[10]``."""
        return np.concatenate([[self.table_height], self.table_tilt, self.patch_centre, self.patch_size,
                               self.sponge_start])

    @classmethod
    def from_vector(cls, v: np.ndarray) -> Context:
        """Inverse of :meth:`vector`."""
        v = np.asarray(v, dtype=np.float64)
        return cls(float(v[0]), v[1:3].copy(), v[3:5].copy(), v[5:7].copy(), v[7:10].copy())


class ContextSpec:
    """Sampling ranges and bounds of the context.

    Args:
        ranges: optional ``{field: (low, high)}`` overrides of the sampling ranges (each a number or
            the field's length of numbers); they must lie within the bounds.
    """

    def __init__(self, ranges: Mapping[str, tuple] | None = None):
        self.low = _SAMPLE_LOW.copy()
        self.high = _SAMPLE_HIGH.copy()
        self.bound_low = _BOUND_LOW.copy()
        self.bound_high = _BOUND_HIGH.copy()
        for key, value in (ranges or {}).items():
            start, length = self._field(key, "context_ranges")
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

    @staticmethod
    def _field(key: str, argument: str) -> tuple[int, int]:
        name = _ALIASES.get(key, key)
        if name not in CONTEXT_FIELDS:
            raise ValueError(f"{argument}: unknown context field {key!r}; expected one of "
                             f"{[*CONTEXT_FIELDS, 'context']}")
        return CONTEXT_FIELDS[name]

    def sample(self, rng: np.random.Generator, options: Mapping | None = None) -> Context:
        """Draw a context from ``rng``; ``options`` fixes fields (or ``context``: the whole vector)."""
        vector = rng.uniform(self.low, self.high)
        for key, value in (options or {}).items():
            if key == "context":
                start, length = 0, SIZE
            else:
                start, length = self._field(key, "options")
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
            vector[part] = array
        return Context.from_vector(vector)
