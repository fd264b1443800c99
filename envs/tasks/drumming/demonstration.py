"""The drumming demonstration: the stick's tip from rest to above the drum, strokes at one tempo, a stop at rest.

Generated in the drum frame (origin at the membrane's centre, z along the drum's axis, m): the tip starts at rest
beside and above the drum, comes in over ``transient`` seconds (a C3 smoothstep blend into the stroke pattern), then
strikes once per period — a vertical stroke from ``top`` above the membrane to ``depth`` below it (the servo and
the membrane stop the stick there), with a small fore-and-aft sway — and after ``n_periods`` periods it lifts off
at the top of a stroke (the strokes fade out within half a period, so the stick never comes down again) and comes
to rest at ``goal`` over ``stop`` seconds, where it stays for ``rest`` seconds.
"""

from __future__ import annotations

import numpy as np

from rdmp_gym import Demonstration

__all__ = ["DEMO_GOAL", "DEMO_START", "drumming_demonstration"]

#: where the demonstrated tip starts and comes to rest (drum frame, m)
DEMO_START = np.array([-0.08, 0.05, 0.09])
DEMO_GOAL = np.array([-0.05, 0.0, 0.07])


def _smoothstep7(u: np.ndarray) -> np.ndarray:
    """C3 step from 0 to 1 over ``u`` in [0, 1] (0 before, 1 after), any shape."""
    u = np.clip(u, 0.0, 1.0)
    return u**4 * (35.0 - 84.0 * u + 70.0 * u**2 - 20.0 * u**3)


def drumming_demonstration(period: float = 0.6, transient: float = 1.5, n_periods: int = 6, stop: float = 1.2,
                           rest: float = 1.0, top: float = 0.018, depth: float = 0.003, sway: float = 0.003,
                           rate: float = 100.0, noise: float = 2e-4, rng: int | np.random.Generator = 0
                           ) -> Demonstration:
    """A demonstration ``Y [L, 3]`` of drumming at one tempo (``period`` s per beat); see the module docstring.

    The stroke's lowest point (``depth`` m below the membrane) comes at phase pi of each period after the
    transient: the strikes are at ``transient + (k + 1/2) period``.
    """
    for name, value in (("period", period), ("transient", transient), ("stop", stop), ("rest", rest),
                        ("top", top), ("rate", rate)):
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"{name}: expected a positive number, got {value!r}")
    if int(n_periods) < 3:
        raise ValueError(f"n_periods: expected at least 3 periods, got {n_periods!r}")
    t = np.arange(0.0, transient + n_periods * period + stop + rest, 1.0 / rate)
    phase = 2.0 * np.pi * (t - transient) / period
    middle, half = 0.5 * (top - depth), 0.5 * (top + depth)
    exit_at = transient + n_periods * period
    fade = 1.0 - _smoothstep7((t - exit_at) / (0.5 * period))          # the strokes end within half a period
    pattern = np.stack([sway * np.sin(phase) * fade, np.zeros_like(t), middle + half * np.cos(phase) * fade], axis=1)
    running = DEMO_START + _smoothstep7(t / transient)[:, None] * (pattern - DEMO_START)
    clean = running + _smoothstep7((t - exit_at) / stop)[:, None] * (DEMO_GOAL - running)
    generator = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    return Demonstration(t=t, Y=clean + noise * generator.standard_normal(clean.shape), name="drumming")
