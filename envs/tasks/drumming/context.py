"""The drumming task's context: where the drum stands, how it is tilted, the tempo, and the tempo change.

The observation is a float32 vector ``[6]``:

    0, 1   drum_position   the membrane centre's x, y in the nominal table frame (m)
    2      drum_height     the membrane's height above the table (m)
    3, 4   drum_tilt       the drum axis' roll about x and pitch about y (rad)
    5      tempo           the metronome's tempo at the start (beats per minute)

The tempo change is drawn per episode and not observed (a drummer hears it, the DMP follows it through its
frequency adaptation): at the beat nearest a time drawn in ``change_window`` (s) the tempo becomes ``tempo *
factor`` with ``factor`` drawn log-uniformly from ``change_factor`` (kept inside ``tempo``'s bounds).
``reset(options=...)`` fixes any field by name (``drum_position``, ``drum_height``, ``drum_tilt``, ``tempo``,
``new_tempo``, ``change_time``); the values are checked against the bounds.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["FIELDS", "DrumContext", "DrumContextSpec"]

#: name -> (first index, length) in the observation
FIELDS: dict[str, tuple[int, int]] = {"drum_position": (0, 2), "drum_height": (2, 1), "drum_tilt": (3, 2),
                                      "tempo": (5, 1)}
_HIDDEN = ("new_tempo", "change_time")


@dataclass(frozen=True)
class DrumContext:
    """One episode's context (see the module docstring)."""

    drum_position: np.ndarray
    drum_height: float
    drum_tilt: np.ndarray
    tempo: float
    new_tempo: float
    change_time: float

    def vector(self) -> np.ndarray:
        """The observation ``[6]`` (float64)."""
        return np.r_[self.drum_position, self.drum_height, self.drum_tilt, self.tempo]


@dataclass(frozen=True)
class DrumContextSpec:
    """Sampling ranges (``reset`` draws from them) and bounds (what options may give) of the context."""

    drum_x: tuple[float, float] = (0.0, 0.10)
    drum_y: tuple[float, float] = (-0.10, 0.06)
    drum_height: tuple[float, float] = (0.09, 0.14)
    drum_tilt: float = 0.1
    tempo: tuple[float, float] = (60.0, 120.0)
    change_factor: tuple[float, float] = (0.8, 1.25)
    change_window: tuple[float, float] = (3.5, 5.5)

    @property
    def low(self) -> np.ndarray:
        """Lower bounds of the observation ``[6]``."""
        return np.array([self.drum_x[0], self.drum_y[0], self.drum_height[0], -self.drum_tilt, -self.drum_tilt,
                         self.tempo[0]])

    @property
    def high(self) -> np.ndarray:
        """Upper bounds of the observation ``[6]``."""
        return np.array([self.drum_x[1], self.drum_y[1], self.drum_height[1], self.drum_tilt, self.drum_tilt,
                         self.tempo[1]])

    def sample(self, rng: np.random.Generator, options: Mapping[str, Any] | None = None) -> DrumContext:
        """Draw a context; ``options`` fix fields by name (checked against the bounds)."""
        options = dict(options or {})
        unknown = set(options) - set(FIELDS) - set(_HIDDEN)
        if unknown:
            raise ValueError(f"options: unknown context fields {sorted(unknown)}; expected some of "
                             f"{[*FIELDS, *_HIDDEN]}")
        low, high = self.low, self.high
        drawn = rng.uniform(low, high)
        factor = float(np.exp(rng.uniform(*np.log(self.change_factor))))
        change = float(rng.uniform(*self.change_window))
        for name, (start, size) in FIELDS.items():
            if name in options:
                value = np.asarray(options[name], dtype=np.float64).reshape(-1)
                if value.shape != (size,) or not np.all(np.isfinite(value)):
                    raise ValueError(f"options: {name} expects {size} finite number(s), got {options[name]!r}")
                if np.any(value < low[start:start + size]) or np.any(value > high[start:start + size]):
                    raise ValueError(f"options: {name} = {value} lies outside {low[start:start + size]}.."
                                     f"{high[start:start + size]}")
                drawn[start:start + size] = value
        tempo = float(drawn[5])
        new_tempo = float(np.clip(tempo * factor, *self.tempo))
        if "new_tempo" in options:
            new_tempo = self._checked(options["new_tempo"], "new_tempo", *self.tempo)
        if "change_time" in options:
            change = self._checked(options["change_time"], "change_time", 0.0, np.inf)
        return DrumContext(drawn[0:2], float(drawn[2]), drawn[3:5], tempo, new_tempo, change)

    @staticmethod
    def _checked(value: Any, name: str, low: float, high: float) -> float:
        number = float(value)
        if not (np.isfinite(number) or number == np.inf) or not low <= number <= high:
            raise ValueError(f"options: {name} expects a number in [{low}, {high}], got {value!r}")
        return number
