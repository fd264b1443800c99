"""The metronome: beats at one tempo that changes once, at a beat, and the beat signal the DMP follows.

The metronome's phase ``psi(t)`` grows at ``2 pi tempo / 60`` rad/s (tempo in beats per minute), from the DMP's
start phase at ``t = 0`` (the count-in is in phase with the movement's start); from the beat at ``change_time`` on
it grows at the new tempo. A beat is where ``psi`` passes the imitation's strike phase (mod 2 pi), so the imitation
at a constant tempo strikes on the beat. The DMP hears the beat signal ``u(t) = cos(psi(t) - shift)``
(:mod:`rdmp_gym.dmp.frequency`: the adaptive oscillator locks onto its phase); ``shift`` (rad) lets a policy strike
earlier or later than the beat to make up for the stick's travel and the servos' lag.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rdmp_gym.validation import check_number, is_number

__all__ = ["Metronome"]


@dataclass(frozen=True)
class Metronome:
    """Beats at ``tempo`` (bpm) until the beat at ``change_time`` (s), at ``new_tempo`` after it.

    Attributes:
        tempo, new_tempo: beats per minute before and after the change.
        change_time: the beat at which the tempo changes (s; beyond the episode: no change).
        start_phase: ``psi(0)`` (rad), the DMP's start phase.
        strike_phase: the phase (rad, mod 2 pi) of a beat.
    """

    tempo: float
    new_tempo: float
    change_time: float
    start_phase: float
    strike_phase: float

    def __post_init__(self) -> None:
        for name in ("tempo", "new_tempo"):
            check_number(getattr(self, name), name, low=0.0, what=" (bpm)")
        if not (is_number(self.change_time) and self.change_time >= 0.0):
            raise ValueError(f"change_time: expected a time >= 0 s or inf (no change), got {self.change_time!r}")
        for name in ("start_phase", "strike_phase"):
            check_number(getattr(self, name), name, what=" (rad)")

    @property
    def omega(self) -> float:
        """The beat's angular frequency before the change (rad/s)."""
        return 2.0 * np.pi * self.tempo / 60.0

    def phase(self, t: np.ndarray) -> np.ndarray:
        """``psi(t)`` (rad, unwrapped) at times ``t [T]`` (s)."""
        t = np.asarray(t, dtype=np.float64)
        new_omega = 2.0 * np.pi * self.new_tempo / 60.0
        before = self.start_phase + self.omega * np.minimum(t, self.change_time)
        return before + new_omega * np.maximum(t - self.change_time, 0.0)

    def beats(self, end: float) -> np.ndarray:
        """The beat times ``[B]`` in ``(0, end]`` (s)."""
        first = np.ceil((self.start_phase - self.strike_phase) / (2.0 * np.pi))
        last = np.floor((self.phase(np.array([end]))[0] - self.strike_phase) / (2.0 * np.pi))
        targets = self.strike_phase + 2.0 * np.pi * np.arange(first, last + 1)
        return self._time_of(targets)

    def _time_of(self, phases: np.ndarray) -> np.ndarray:
        """The times ``[K]`` at which ``psi`` reaches ``phases [K]`` (rad, increasing)."""
        times = (phases - self.start_phase) / self.omega
        if np.isfinite(self.change_time):
            at_change = self.start_phase + self.omega * self.change_time
            after = phases > at_change
            times[after] = self.change_time + (phases[after] - at_change) / (2.0 * np.pi * self.new_tempo / 60.0)
        return times[times > 0.0]

    def signal(self, t: np.ndarray, shift: float = 0.0) -> np.ndarray:
        """The beat signal ``cos(psi(t) - shift)`` at times ``t [T]``."""
        return np.cos(self.phase(t) - shift)

    @classmethod
    def changing_at_beat(cls, tempo: float, new_tempo: float, near: float, start_phase: float,
                         strike_phase: float) -> Metronome:
        """A metronome whose tempo changes at the beat (of the first tempo) nearest to ``near`` (s; inf: never)."""
        steady = cls(tempo, tempo, np.inf, start_phase, strike_phase)
        if not (is_number(near) and near >= 0.0):
            raise ValueError(f"near: expected a time >= 0 s or inf (no change), got {near!r}")
        if not np.isfinite(near):
            return steady
        beats = steady.beats(near + 60.0 / tempo)
        change = float(beats[np.argmin(np.abs(beats - near))])
        return cls(tempo, new_tempo, change, start_phase, strike_phase)
