"""Parameters that change from one cycle to the next: a cycle schedule of a rhythmic DMP.

A reacting policy chooses the DMP's parameters at the start of every cycle from what it observes there. Cycle ``k``
starts at the ``k``-th crossing of the canonical phase through its initial value after the transient
(:func:`cycle_starts`; cycle 0 starts at the movement's start and holds the transient). From its start on, cycle
``k``'s parameters take over from the movement so far within a hand-over window:

    y(t) = y_before(t) + s((t - t_k) / w) (y_k(t) - y_before(t)),

``y_k`` the rollout of cycle ``k``'s parameters, ``y_before`` the movement so far, ``s`` the septic smoothstep
(:func:`handover_ramp`: 0 up to the crossing, 1 from ``t_k + w`` on, its first three derivatives 0 at both ends).
So the path is unchanged up to the crossing, it is the new parameters' own rollout from the end of the window on,
and it is C3 at both ends of the window (position, velocity, acceleration and jerk are continuous). A cycle whose
parameters equal the previous cycle's changes nothing, bit for bit.

The online integrator follows the same schedule: :meth:`rdmp_gym.DMPStepper.change_weights` hands a
running stepper over to new forcing weights from the next cycle start (:func:`next_cycle_start`) or from a given
time on. The transformation system is linear in the forcing term, so ``delta = y_k - y_before`` is the response
from rest at the movement's start to the difference of the two parameters' inputs. The stepper integrates it from
the start up to the request, then step by step beside its own state; it outputs ``y_before + s delta`` and adds
``delta`` to its own state at the end of the window. Without a coupling term its path is that of
:func:`rollout_cycles`; a coupling term acts on the stepper's own state, with or without a change.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ..validation import as_finite_array

if TYPE_CHECKING:
    from .rhythmic import RhythmicDMP

__all__ = ["DEFAULT_HANDOVER", "blend_from", "cycle_starts", "handover_ramp", "handover_ramp_rate", "handover_width",
           "next_cycle_start", "rollout_cycles"]

#: the hand-over window as a fraction of the period (half a cycle: a change of the size a learner explores hands
#: over with no more jerk than the rollouts of either parameters have of their own)
DEFAULT_HANDOVER = 0.5


def handover_ramp(t: np.ndarray, start: float, width: float) -> np.ndarray:
    """``s [T]``: 0 for ``t <= start``, 1 for ``t >= start + width``, the septic smoothstep
    ``35 u^4 - 84 u^5 + 70 u^6 - 20 u^7`` of ``u = (t - start) / width`` in between (C3 at both ends)."""
    u = _ramp_argument(t, start, width)
    return np.minimum(u**4 * (35.0 + u * (-84.0 + u * (70.0 - 20.0 * u))), 1.0)     # round-off above 1 near u = 1


def handover_ramp_rate(t: np.ndarray, start: float, width: float) -> np.ndarray:
    """``ds/dt [T]`` (1/s) of :func:`handover_ramp`: ``140 u^3 (1 - u)^3 / width``, 0 outside the window."""
    u = _ramp_argument(t, start, width)
    return 140.0 * (u * (1.0 - u)) ** 3 / width


def _ramp_argument(t: np.ndarray, start: float, width: float) -> np.ndarray:
    """``u = (t - start) / width`` clipped to [0, 1], ``[T]``."""
    if not (np.isfinite(width) and width > 0):
        raise ValueError(f"width: expected a finite number > 0 (s), got {width!r}")
    return np.clip((np.asarray(t, dtype=np.float64) - start) / width, 0.0, 1.0)


def handover_width(dmp: RhythmicDMP, handover: float, tempo: float | None = None) -> float:
    """The hand-over window (s) of ``handover`` periods of ``dmp`` at its tempo (or at ``tempo``)."""
    if not (np.isfinite(handover) and handover > 0):
        raise ValueError(f"handover: expected a finite number > 0 (periods), got {handover!r}")
    return handover * _period(dmp, tempo)


def blend_from(before: np.ndarray, after: np.ndarray, t: np.ndarray, start: float, width: float) -> np.ndarray:
    """The path ``[T, d]`` that follows ``before [T, d]`` up to ``start`` and hands over to ``after [T, d]`` within
    ``width`` (s): exactly ``before`` up to ``start`` and exactly ``after`` from ``start + width`` on."""
    if before.shape != after.shape or before.shape[0] != len(t):
        raise ValueError(f"before, after: expected two paths of shape [{len(t)}, d], got {before.shape} and "
                         f"{after.shape}")
    ramp = handover_ramp(t, start, width)
    out = before.copy()
    moving = (ramp > 0.0) & (ramp < 1.0)
    out[moving] += ramp[moving, None] * (after[moving] - before[moving])
    out[ramp >= 1.0] = after[ramp >= 1.0]
    return out


def cycle_starts(dmp: RhythmicDMP, duration: float, transient: int = 0, tempo: float | None = None) -> np.ndarray:
    """``[K]`` start times (s) of the cycles of a movement of ``duration`` s: 0, then every crossing of the canonical
    phase through transient ``transient``'s initial phase after that transient has ended (one period apart at the
    DMP's tempo, or at ``tempo``) that leaves at least half a period before ``duration``."""
    if not (np.isfinite(duration) and duration > 0):
        raise ValueError(f"duration: expected a finite number > 0 (s), got {duration!r}")
    start = dmp.transients[dmp._check_transient(transient)]
    period = _period(dmp, tempo)
    first = np.ceil(start.length / dmp.period - 1e-9)       # the transient's length in cycles, the same at any tempo
    crossings = period * np.arange(max(first, 1.0), np.floor(duration / period - 1e-9) + 1.0)
    return np.r_[0.0, crossings[crossings <= duration - 0.5 * period]]


def _speed(dmp: RhythmicDMP, tempo: float | None) -> float:
    """The speed factor of a rollout at ``tempo`` (``None``: the canonical system's own)."""
    speed = dmp.canonical.tempo if tempo is None else float(tempo)
    if not (np.isfinite(speed) and speed > 0):
        raise ValueError(f"tempo: expected a finite number > 0, got {tempo!r}")
    return speed


def _period(dmp: RhythmicDMP, tempo: float | None) -> float:
    """The period (s) of ``dmp`` at ``tempo`` (``None``: its own): its unit-tempo period over the speed factor."""
    return dmp.period / _speed(dmp, tempo)


def next_cycle_start(dmp: RhythmicDMP, time: float, transient: int = 0, tempo: float | None = None) -> float:
    """The first cycle start after the transient (an entry of :func:`cycle_starts` other than 0) at or after
    ``time`` (s since the start)."""
    length = dmp.transients[dmp._check_transient(transient)].length / _speed(dmp, tempo)
    horizon = max(time, length) + 2.0 * _period(dmp, tempo)
    crossings = cycle_starts(dmp, horizon, transient, tempo)[1:]
    return float(crossings[crossings >= time][0])


def rollout_cycles(dmp: RhythmicDMP, thetas: np.ndarray, t: np.ndarray, starts: np.ndarray,
                   handover: float = DEFAULT_HANDOVER, **rollout: Any) -> np.ndarray:
    """The path ``[T, d]`` of a cycle schedule: cycle ``k`` (starting at ``starts[k]``, s from ``t[0]``) runs the
    parameters ``thetas[k]`` (``[K, P]``, the groups of ``rollout["groups"]``), handed over within ``handover``
    periods (see the module docstring). ``rollout``: the keywords of :meth:`RhythmicDMP.rollout_batch`, the same
    for every cycle; the window is ``handover`` periods at its ``tempo``. Equal consecutive rows change nothing: with
    all rows equal the path is ``rollout_batch(thetas[:1], t, ...)[0]`` bit for bit."""
    thetas = as_finite_array(thetas, "thetas", ndim=2)
    starts = as_finite_array(starts, "starts", ndim=1)
    if len(starts) != len(thetas) or np.any(np.diff(starts) <= 0):
        raise ValueError(f"starts: expected {len(thetas)} increasing times (one per row of thetas), got {starts}")
    width = handover_width(dmp, handover, rollout.get("tempo"))
    t = np.asarray(t, dtype=np.float64)
    path = dmp.rollout_batch(thetas[:1], t, **rollout)[0]
    for k in range(1, len(thetas)):
        if np.array_equal(thetas[k], thetas[k - 1]):
            continue
        after = dmp.rollout_batch(thetas[k:k + 1], t, **rollout)[0]
        path = blend_from(path, after, t - t[0], float(starts[k]), width)
    return path
