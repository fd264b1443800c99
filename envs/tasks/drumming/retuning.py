"""The drumming task's second version: a policy that hears the tempo change may retune the rhythm follower.

:class:`DrumTask` (version 1) gives a policy the follower's gains and the beat's shift, and the follower adapts its
frequency to a tempo change on its own: a policy cannot make it adapt faster, and a follower tuned for a rise of the
tempo lags a fall (``benchmarks/bench_drum_timing.py``: one setting of the three values succeeds in 0.83 of the
contexts; with the follower set to the new tempo at the first cycle after the change, 1.00).
:class:`RetuningDrumTask` (``rdmp_gym/ArmarDrum-v2``, ``rdmp_gym/PandaDrum-v2``) adds what that takes:

- a fourth value, ``ear`` ``a``: how much the follower listens to the tempo. Every beat, :data:`HEARING` seconds
  after it, the follower's frequency moves the share ``g = clip(4 a, 0, 1)`` of the way to the beat signal's tempo
  heard over those seconds (``g = 0``, the action 0 and below: version 1's follower; ``g = 1`` from ``a = 0.25``:
  it takes the heard tempo; the scale puts the whole range within a learner's first exploration). A learned
  feedback gain of the follower, chosen once per episode or per cycle;
- a fifth value, ``tempo`` ``a``: the follower's frequency at the plan's start is the announced tempo's times
  ``2^(a / 2)``; on the cycle-level face, a cycle whose ``tempo`` differs from the running one's sets the
  follower's frequency to that from its start (the follower adapts on from there), and an equal one leaves it as
  it is;
- what a policy hears at a cycle's start: after version 1's state (the tip, the last two beats' timing errors, the
  last one's miss), the beat signal's tempo over the last :data:`HEARING` seconds, as ``log2`` of its ratio to the
  announced tempo (0 before the change);
- a cycle that starts after the stop's request changes nothing: the stop is under way (in version 1, a change of
  the amplitude in the last cycle moves the stick's rest and fails the rest at the end).

Everything else (the scene, the beats, the judgement) is version 1's; the action 0 plays as version 1's does.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from rdmp_gym import RhythmicDMP
from rdmp_gym.dmp.frequency import Retunes

from ..description import TaskPlan
from .context import DrumContext
from .metronome import Metronome
from .task import DrumTask

__all__ = ["HEARING", "RetuningDrumTask", "heard_frequency"]

#: the span (s) over which the policy hears the beat signal's tempo before a cycle's start
HEARING = 0.1
#: the task's values in the action's extras: the ear's gain and the tempo
_EAR, _TEMPO = 3, 4
#: the bound of the heard tempo's log2 ratio to the announced one (the context's changes stay within +-0.33)
_HEARD_BOUND = 1.0


class RetuningDrumTask(DrumTask):
    """The drumming task with the follower's ``ear`` and ``tempo`` values and the heard tempo (see the module
    docstring); the settings are :class:`DrumTask`'s."""

    versions = (2,)
    extras: Mapping[str, float] = {**DrumTask.extras, "ear": 4.0, "tempo": 1.0}

    def plan(self, dmp: RhythmicDMP, theta: np.ndarray, extras: np.ndarray, context: DrumContext,
             times: np.ndarray, table_origin: np.ndarray) -> TaskPlan:
        plan = super().plan(dmp, theta, extras, context, times, table_origin)
        return TaskPlan(plan.path, plan.origin, plan.rotation, {**plan.extras, "tempo": float(extras[_TEMPO])})

    def resume_plan(self, live: TaskPlan, step: int, dmp: RhythmicDMP, theta: np.ndarray, extras: np.ndarray,
                    context: DrumContext, times: np.ndarray, table_origin: np.ndarray) -> TaskPlan:
        """Version 1's resumed plan; a ``tempo`` other than the running plan's sets the follower's frequency at
        ``step`` to the announced tempo's times ``2^(tempo / 2)``. From the stop's request on (control step) the
        running plan goes on: the stop is under way."""
        if step >= np.searchsorted(times, live.extras["stop_at"]):
            return live
        tempo = float(extras[_TEMPO])
        retune = None if tempo == live.extras["tempo"] else self._frequency(self.metronome(context), tempo)
        plan = self._resumed(live, step, dmp, theta, extras, context, times, retune)
        return TaskPlan(plan.path, plan.origin, plan.rotation, {**plan.extras, "tempo": tempo})

    def _rhythm(self, extras: np.ndarray, metronome: Metronome, times: np.ndarray
                ) -> tuple[dict[str, float], np.ndarray]:
        """Version 1's settings of the first three values, the follower starting at the frequency of ``tempo``."""
        settings, signal = DrumTask._rhythm(extras[:3], metronome, times)
        return {**settings, "frequency": self._frequency(metronome, float(extras[_TEMPO]))}, signal

    @staticmethod
    def _retunes(extras: np.ndarray, metronome: Metronome, times: np.ndarray) -> Retunes | None:
        """The ear's corrections (see the module docstring) at the control times ``times [T]``: None at gain 0."""
        gain = float(np.clip(extras[_EAR], 0.0, 1.0))            # the action's a times the value's scale, 4
        if gain == 0.0:
            return None
        steps = np.unique(np.searchsorted(times, metronome.beats(float(times[-1])) + HEARING))
        steps = steps[steps < times.size]
        targets = [heard_frequency(metronome, float(times[k])) for k in steps]
        return Retunes(steps, np.array(targets), gain)

    @staticmethod
    def _frequency(metronome: Metronome, tempo: float) -> float:
        """The follower's frequency (rad/s) of the ``tempo`` value: the announced tempo's times ``2^(tempo / 2)``."""
        return metronome.omega * 2.0 ** (0.5 * tempo)

    # ------------------------------------------------------------------ the cycle-level face
    def cycle_state_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Version 1's, then the heard tempo (``log2`` of its ratio to the announced one, within +-1)."""
        low, high = super().cycle_state_bounds()
        return np.r_[low, -_HEARD_BOUND], np.r_[high, _HEARD_BOUND]

    def cycle_state(self, face: Any, step: int | None, overlay: Any) -> np.ndarray:
        """Version 1's, then the beat signal's tempo over the :data:`HEARING` s before control step ``step``
        (``log2`` of its ratio to the announced tempo; 0 at rest before the first cycle)."""
        heard = 0.0
        if step is not None and step > 0:
            metronome = self.metronome(face.context)
            heard = float(np.log2(heard_frequency(metronome, step * face.dt) / metronome.omega))
        return np.r_[super().cycle_state(face, step, overlay), heard]


def heard_frequency(metronome: Metronome, now: float) -> float:
    """The beat signal's frequency (rad/s) heard over the :data:`HEARING` s before ``now`` (s, > 0; from 0 where
    the episode is younger)."""
    since = max(now - HEARING, 0.0)
    return float(np.diff(metronome.phase(np.array([since, now])))[0] / (now - since))
