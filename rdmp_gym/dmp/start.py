"""The start of a movement: what an encoded transient records, and the smooth start's profiles.

* :class:`TransientStart`: where the canonical system starts for one encoded transient and where its
  demonstration started.
* :func:`start_blend_profiles`: the quintic profiles that move a start offset away over the transient (C2).
* :func:`blend_shift`: the anchor shift that makes the spring follow those profiles exactly.
* :func:`settled_state`: the state the forcing term holds at the start (the spring's equilibrium, at rest).

The fit (:mod:`rdmp_gym.dmp.fitting`), the rollout (:mod:`rdmp_gym.dmp.rhythmic`) and the online steppers
(:mod:`rdmp_gym.dmp.frequency`) use them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["TransientStart", "blend_shift", "settled_state", "start_blend_profiles"]


@dataclass(frozen=True)
class TransientStart:
    """One encoded transient: where the canonical system starts and where the demonstration started.

    Attributes:
        phi0, r0: initial condition of the canonical system, ``init_T(entrance_phase, mu1)``.
        length: transient length T_k of the demonstration (s).
        entrance_phase: phase at which the transient enters the periodic pattern (rad).
        start: ``[d]`` start position of the demonstration (fitted with the weights by ``trajectory``; the
            smoothed first sample otherwise).
        start_velocity: ``[d]`` its start velocity (fitted under the smooth-start model: a derivative
            estimate at the first noisy sample is off by up to 0.1 m/s).
    """

    phi0: float
    r0: float
    length: float
    entrance_phase: float
    start: np.ndarray
    start_velocity: np.ndarray


def start_blend_profiles(elapsed: np.ndarray, length: float) -> np.ndarray:
    """Quintic profiles of the start blend and their first two time derivatives, ``[2, 3, T]``.

    Profile 0 falls from 1 to 0 with zero slope and curvature at both ends (minimum jerk); profile 1
    has slope 1 and zero value and curvature at the start. Both are 0 with zero derivatives from
    ``length`` on, so ``e(t) = dy P0(t) + dv P1(t)`` moves a start offset ``(dy, dv)`` away smoothly (C2).
    """
    u = np.clip(elapsed / length, 0.0, 1.0)
    fall = np.stack([1.0 - u**3 * (10.0 - 15.0 * u + 6.0 * u**2),
                     -30.0 * u**2 * (1.0 - u) ** 2 / length,
                     -60.0 * u * (1.0 - u) * (1.0 - 2.0 * u) / length**2])
    slope = np.stack([length * u * (1.0 - u) ** 3 * (1.0 + 3.0 * u),
                      (1.0 - u) ** 2 * (1.0 + 2.0 * u - 15.0 * u**2),
                      -12.0 * u * (1.0 - u) * (3.0 - 5.0 * u) / length])
    return np.stack([fall, slope])


def settled_state(forcing: np.ndarray, anchor: np.ndarray, alpha_z: float) -> tuple[np.ndarray, np.ndarray]:
    """The state ``(y, yd)`` ``[..., d]`` that the forcing term ``[..., d]`` holds at the start: the spring's
    equilibrium ``g + f / (alpha_z beta_z)``, at rest. From there the acceleration starts at 0 and the spring
    follows the forcing term with no fast transient of its own (for a demonstration that starts at rest,
    this is about its start)."""
    return anchor + forcing / (alpha_z * alpha_z / 4.0), np.zeros_like(anchor + forcing)


def blend_shift(elapsed: np.ndarray, length: np.ndarray, offset: np.ndarray, velocity_offset: np.ndarray,
                omega: float, alpha_z: float) -> np.ndarray:
    """Anchor shift ``[B, T, d]`` whose response is exactly ``e(t) = dy P0(t) + dv P1(t)`` (lengths ``[B]``,
    offsets ``[B, d]``): ``dg = e + de/dt / (beta_z Omega) + d2e/dt2 / (alpha_z beta_z Omega^2)``.

    The smooth start of a rollout (and of an online stepper) moves a start offset away by shifting the anchor by
    this over the first ``length`` seconds (``elapsed [T]``, s); a tempo so small that ``omega**2`` underflows gives
    inf/NaN, which the caller refuses."""
    beta_z = alpha_z / 4.0
    lengths, row_length = np.unique(length, return_inverse=True)          # the profiles once per distinct length
    with np.errstate(all="ignore"):      # a tempo so small that omega**2 underflows: inf/NaN (see above)
        gains = 1.0 / np.array([1.0, beta_z * omega, alpha_z * beta_z * np.float64(omega) ** 2])
        profiles = np.stack([gains @ start_blend_profiles(elapsed, float(value)) for value in lengths])
        if lengths.size > 1:
            profiles = profiles[row_length.ravel()]                                     # [B, 2, T]
        shift = profiles[:, 0, :, None] * offset[:, None, :]
        for dim in range(shift.shape[-1]):          # one coordinate at a time: a [B, T] temporary, not [B, T, d]
            shift[..., dim] += profiles[:, 1] * velocity_offset[:, None, dim]
        return shift
