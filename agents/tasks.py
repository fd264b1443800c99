"""What the agents run on: an environment id, its ``gym.make`` keywords and fixed reset options."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import gymnasium as gym
import numpy as np

__all__ = ["WIPE_ID", "TaskSpec", "episode_metrics"]

WIPE_ID = "rdmp_gym/ArmarWipe-v0"


@dataclass(frozen=True)
class TaskSpec:
    """A picklable recipe for the task's environment (worker processes rebuild it from this).

    Attributes:
        env_id: a registered episodic env (``rdmp_gym/ArmarWipe-v0`` or ``rdmp_gym/DMPTracking-v0``).
        env_kwargs: keywords for ``gym.make`` (style, groups, n_periodic, duration, ...).
        reset_options: ``options`` passed to every ``reset`` (e.g. to fix the context), or None.
    """

    env_id: str = WIPE_ID
    env_kwargs: Mapping[str, Any] = field(default_factory=dict)
    reset_options: Mapping[str, Any] | None = None

    def make(self, render_mode: str | None = None) -> gym.Env:
        """Build the environment (importing the packages that register the ids)."""
        import rdmp_gym  # noqa: F401  (registers rdmp_gym/ArmarWipe-v0)

        from . import tracking  # noqa: F401  (registers rdmp_gym/DMPTracking-v0)

        extra = {} if render_mode is None else {"render_mode": render_mode}
        return gym.make(self.env_id, disable_env_checker=True, **dict(self.env_kwargs), **extra)

    def options(self) -> dict[str, Any] | None:
        """A fresh copy of the reset options."""
        return None if self.reset_options is None else dict(self.reset_options)


def episode_metrics(reward: float, info: Mapping[str, Any]) -> dict[str, Any]:
    """The numbers the agents use from one episodic ``step``: return, cost trace ``[T]`` and task metrics.

    ``coverage`` and ``force_in_band_fraction`` are NaN for tasks that have no dirt or contact.
    """
    if "cost_trace" not in info:
        raise ValueError("info: the env returned no 'cost_trace' (per-control-step cost), which the agents need")
    return {"return": float(reward),
            "cost_trace": np.asarray(info["cost_trace"], dtype=np.float64),
            "coverage": float(info.get("coverage", np.nan)),
            "force_in_band": float(info.get("force_in_band_fraction", np.nan)),
            "valid": bool(info.get("valid", True))}
