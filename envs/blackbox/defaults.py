"""Defaults of the rhythmic black-box wrapper: the action scales, the default pattern, settings per known env.

Without a demonstration the wrapper fits its DMP to :func:`default_demonstration`: one sine per joint about a
posture, the same period for all, each joint with its own phase, that grows from rest at the posture over the
first period (a smoothstep envelope), so the fitted transient is a gentle start into the rhythm.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from rdmp_gym import Demonstration, Segmentation

__all__ = ["BLACKBOX_SCALES", "ENV_DEFAULTS", "default_demonstration", "env_defaults", "pattern_phases"]

#: Action scales (``theta = theta0 + scale * a``). ``periodic``/``transient``: the fraction of the range of the
#: initial DMP's weights per joint (as :class:`rdmp_gym.envs.action.ActionMap` does); ``initial``: of pi for the
#: phase and of r0 for the radius; ``amplitude``: the factor on the pattern about the anchor, so ``a = +-1`` scales
#: it by 1.5 / 0.5; ``anchor``: the fraction of each joint's peak-to-peak motion in the initial DMP's cycle
#: (floored at a quarter of the largest joint's), so the unit-free value suits hinges (rad) and slides (m) alike;
#: ``tempo``: the change of the speed factor at ``a = +-1`` (0.5: 1.5x faster / half speed).
BLACKBOX_SCALES: dict[str, float] = {"periodic": 0.5, "transient": 0.5, "initial": 0.1, "amplitude": 0.5,
                                     "anchor": 0.5, "tempo": 0.5}

#: Settings of the wrapper for Gymnasium MuJoCo envs, by the env spec's name (no version); keywords given to
#: :func:`~rdmp_gym.envs.blackbox.make_blackbox` replace them. Both follow the open-loop baseline of Raffin et al.
#: 2024 (An Open-Loop Baseline for Reinforcement Learning Locomotion Tasks, arXiv 2310.05808,
#: https://arxiv.org/html/2310.05808v3): one sine per joint, one frequency shared by all joints, a phase per joint,
#: tracked by a PD controller on the env's torque action.
#:
#: - ``Swimmer``: their published oscillator (0.62 Hz, phases 0 and 0.95 x 2 pi, PD gains 10 and 0.5 in action
#:   units per rad and rad/s; the code on their RLC 2024 slides), at half their amplitude of 1 rad.
#: - ``HalfCheetah``: their recipe, but not their numbers (their HalfCheetah gains, frequency and phases could not be
#:   read from the sources at hand): 3 Hz, joint j (``bthigh, bshin, bfoot, fthigh, fshin, ffoot``) at phase
#:   ``j pi / 3``, 0.5 rad, PD gains 1 (action units per rad; the motors' gears are 30-120 Nm) and 0.02 per rad/s.
#:   Chosen here as the best of 132 settings (gains 0.5-3 / 0.02-0.1, 2-5 Hz, lags 0 to pi, 0.3-0.7 rad) by the
#:   return of ``a = 0``: about 650 on HalfCheetah-v5 (reset seeds 100-103), tracking RMS 0.29 rad, nothing clipped.
ENV_DEFAULTS: dict[str, dict[str, Any]] = {
    "Swimmer": {"controller": "pd", "p_gains": 10.0, "d_gains": 0.5, "period": 1.0 / 0.62,
                "phases": (0.0, 0.95 * 2.0 * np.pi), "amplitude": 0.5},
    "HalfCheetah": {"controller": "pd", "p_gains": 1.0, "d_gains": 0.02, "period": 1.0 / 3.0,
                    "phases": -np.pi / 3.0, "amplitude": 0.5},
}


def env_defaults(env_id: str) -> dict[str, Any]:
    """A copy of :data:`ENV_DEFAULTS` for ``env_id`` (``"Swimmer-v5"``, ``"gymnasium/Swimmer-v5"``, or a name
    without version); ``{}`` for an env without entry."""
    name = env_id.rsplit("/", 1)[-1].rsplit(":", 1)[-1]
    head, _, version = name.rpartition("-v")
    if head and version.isdigit():
        name = head
    return dict(ENV_DEFAULTS.get(name, {}))


def pattern_phases(phases: float | Sequence[float] | None, n_joints: int) -> np.ndarray:
    """``[d]`` phases (rad) of the default pattern's sines: given per joint, or a number ``lag``: joint j at
    ``-j * lag`` (a wave travelling from the first joint to the last); ``None``: a lag of pi/2."""
    if phases is None:
        phases = 0.5 * np.pi
    values = np.asarray(phases, dtype=np.float64)
    if values.ndim == 0:
        values = -float(values) * np.arange(n_joints)
    if values.shape != (n_joints,) or not np.all(np.isfinite(values)):
        raise ValueError(f"phases: expected a number (the lag between neighbouring joints) or {n_joints} finite "
                         f"phases (rad), got {phases!r}")
    return values


def default_demonstration(posture: np.ndarray, period: float, amplitude: float | Sequence[float],
                          phases: float | Sequence[float] | None = None, rate: float = 100.0,
                          cycles: int = 4) -> tuple[Demonstration, Segmentation]:
    """The default pattern and its segmentation: ``y_j(t) = posture_j + s(t / T) A_j sin(2 pi t / T + phi_j)``.

    Args:
        posture: ``[d]`` the anchor (the joints' rest posture).
        period: T (s), also the length of the start (the transient).
        amplitude: ``A`` (joint units), a number or ``[d]``, each > 0.
        phases: see :func:`pattern_phases`.
        rate: samples per second.
        cycles: whole periods after the start.
    Returns:
        the demonstration (starting at rest at the posture) and its known segmentation.
    """
    posture = np.asarray(posture, dtype=np.float64)
    if posture.ndim != 1 or posture.size == 0 or not np.all(np.isfinite(posture)):
        raise ValueError(f"posture: expected [d] finite joint positions, got {posture!r}")
    d = posture.size
    period = float(period)
    if not (np.isfinite(period) and period > 0.0):
        raise ValueError(f"period: expected a duration > 0 s, got {period!r}")
    amplitudes = np.broadcast_to(np.asarray(amplitude, dtype=np.float64), (d,)) if np.ndim(amplitude) == 0 \
        else np.asarray(amplitude, dtype=np.float64)
    if amplitudes.shape != (d,) or not np.all(np.isfinite(amplitudes)) or np.any(amplitudes <= 0.0):
        raise ValueError(f"amplitude: expected a number or {d} numbers > 0 (joint units), got {amplitude!r}")
    phi = pattern_phases(phases, d)
    t = np.arange(round((cycles + 1) * period * rate) + 1) / rate
    u = np.clip(t / period, 0.0, 1.0)
    envelope = u**3 * (10.0 - 15.0 * u + 6.0 * u**2)
    Y = posture + envelope[:, None] * amplitudes * np.sin(2.0 * np.pi * t[:, None] / period + phi)
    return (Demonstration(t, Y, name="default rhythmic pattern"),
            Segmentation(period=period, transient_length=period, anchor=posture.copy()))
