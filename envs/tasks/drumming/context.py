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
``new_tempo``, ``change_time``); the values are checked for type and against the bounds: ``change_time`` lies in
the episode (the beat nearest it no later than the episode's last beat), or is ``inf``: the tempo never changes and
``new_tempo`` is ``tempo``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from rdmp_gym.validation import SettingTypeError, check_number, check_pair, is_number

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
    """Sampling ranges (``reset`` draws from them) and bounds (what options may give) of the context.

    Each range is ``(low, high)``, two finite numbers with ``low <= high``; ``drum_height``, ``tempo`` and
    ``change_factor`` have ``low > 0``, ``change_window`` (s) ``low >= 0``; ``drum_tilt`` (rad) lies in ``[0, pi/2)``.
    Anything else is a ValueError naming the field (a TypeError for a value that is not a number).
    """

    drum_x: tuple[float, float] = (0.0, 0.10)
    drum_y: tuple[float, float] = (-0.10, 0.06)
    drum_height: tuple[float, float] = (0.09, 0.14)
    drum_tilt: float = 0.1
    tempo: tuple[float, float] = (60.0, 120.0)
    change_factor: tuple[float, float] = (0.8, 1.25)
    change_window: tuple[float, float] = (3.5, 5.5)

    def __post_init__(self) -> None:
        for name, bound in _RANGES.items():
            low, high = check_pair(getattr(self, name), name, "a range (low, high)")
            if low > high or (bound == "> 0" and low <= 0.0) or (bound == ">= 0" and low < 0.0):
                extra = f" and low {bound}" if bound else ""
                raise ValueError(f"{name}: expected (low, high) with low <= high{extra}, got {getattr(self, name)!r}")
            object.__setattr__(self, name, (low, high))
        tilt = check_number(self.drum_tilt, "drum_tilt", low=0.0, strict_low=False, what=" (rad)")
        if tilt >= 0.5 * np.pi:
            raise ValueError(f"drum_tilt: expected a tilt bound in [0, pi/2) rad, got {self.drum_tilt!r}")
        object.__setattr__(self, "drum_tilt", tilt)

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

    @staticmethod
    def latest_change(last_beat: float, tempo: float) -> float:
        """The latest change time (s) whose beat, the one nearest it at ``tempo`` (bpm), comes by ``last_beat`` (s):
        half a beat before it."""
        return last_beat - 30.0 / tempo

    def sample(self, rng: np.random.Generator, options: Mapping[str, Any] | None = None,
               last_beat: float = np.inf) -> DrumContext:
        """Draw a context; ``options`` fix fields by name, checked for type and against the bounds: the observed
        fields and ``new_tempo`` against the ranges, ``change_time`` (s) against the episode, whose last beat is at
        ``last_beat`` (s; the task's), or ``inf``: the tempo never changes, and ``new_tempo`` is ``tempo``."""
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
                value = _numbers(options[name], name, size)
                if np.any(value < low[start:start + size]) or np.any(value > high[start:start + size]):
                    raise ValueError(f"options: {name} = {value} lies outside {low[start:start + size]}.."
                                     f"{high[start:start + size]}")
                drawn[start:start + size] = value
        tempo = float(drawn[5])
        new_tempo = float(np.clip(tempo * factor, *self.tempo))
        if "new_tempo" in options:
            new_tempo = float(_numbers(options["new_tempo"], "new_tempo", 1)[0])
            if not self.tempo[0] <= new_tempo <= self.tempo[1]:
                raise ValueError(f"options: new_tempo expects a number in [{self.tempo[0]}, {self.tempo[1]}] (bpm), "
                                 f"got {options['new_tempo']!r}")
        if "change_time" in options:
            change = self._change_time(options["change_time"], tempo, last_beat)
            if change == np.inf:
                if "new_tempo" in options and new_tempo != tempo:
                    raise ValueError(f"options: new_tempo = {new_tempo:g} differs from tempo = {tempo:g}, but "
                                     "change_time = inf never changes the tempo; give a finite change_time")
                new_tempo = tempo
        return DrumContext(drawn[0:2], float(drawn[2]), drawn[3:5], tempo, new_tempo, change)

    def _change_time(self, value: Any, tempo: float, last_beat: float) -> float:
        """The ``change_time`` option (s) at ``tempo`` (bpm): a time whose beat comes by ``last_beat`` (s), or inf."""
        if is_number(value) and float(value) == np.inf:
            return np.inf
        number = float(_numbers(value, "change_time", 1)[0])
        latest = self.latest_change(last_beat, tempo)
        if not 0.0 <= number <= latest:
            raise ValueError(f"options: change_time expects a time in [0, {latest:g}] s or inf (no change), got "
                             f"{value!r}: the tempo changes at the beat nearest it, which must come by the episode's "
                             f"last beat at {last_beat:g} s (at {tempo:.4g} bpm)")
        return number


#: range field -> what its low must be ("": anything)
_RANGES = {"drum_x": "", "drum_y": "", "drum_height": "> 0", "tempo": "> 0", "change_factor": "> 0",
           "change_window": ">= 0"}


def _numbers(value: Any, name: str, size: int) -> np.ndarray:
    """The option ``name`` as ``size`` finite numbers ``[size]`` (float64); a SettingTypeError for what is not numbers
    (bools and strings too), a ValueError for a wrong count or NaN/inf."""
    try:
        array = np.asarray(value)
    except (TypeError, ValueError):
        array = np.asarray(None)
    if array.dtype.kind not in "iuf":
        raise SettingTypeError(f"options: {name} expects {size} number(s), got {value!r} ({type(value).__name__})")
    array = array.astype(np.float64).reshape(-1)
    if array.shape != (size,) or not np.all(np.isfinite(array)):
        raise ValueError(f"options: {name} expects {size} finite number(s), got {value!r}")
    return array
