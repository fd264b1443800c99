"""The start of a movement: what an encoded transient records, and the smooth start's profiles.

* :class:`TransientStart`: where the canonical system starts for one encoded transient and where its
  demonstration started.
* :func:`start_blend_profiles`: the quintic profiles that move a start offset away over the transient (C2).
* :func:`settled_state`: the state the forcing term holds at the start (the spring's equilibrium, at rest).

Both the fit (:mod:`rdmp_gym.fitting`) and the rollout (:mod:`rdmp_gym.dmp`) use them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["TransientStart", "settled_state", "start_blend_profiles"]


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
