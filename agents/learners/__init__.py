"""Episodic learners behind one ask/tell interface: PI², PI^BB and CMA-ES."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ..options import from_options
from .base import EpisodeBatch, Learner, cost_weights
from .cmaes import CMAES, CMAESConfig
from .pi2 import PI2, PI2Config
from .pibb import PIBB, PIBBConfig

__all__ = ["CMAES", "LEARNERS", "PI2", "PIBB", "CMAESConfig", "EpisodeBatch", "Learner", "PI2Config",
           "PIBBConfig", "cost_weights", "make_learner"]

LEARNERS: dict[str, tuple[type[Learner], type]] = {
    "pi2": (PI2, PI2Config),
    "pibb": (PIBB, PIBBConfig),
    "cmaes": (CMAES, CMAESConfig),
}


def make_learner(agent: str, initial_mean: np.ndarray, rollouts: int, rng: np.random.Generator,
                 options: Mapping[str, Any] | None = None, time_weights: np.ndarray | None = None) -> Learner:
    """Create the learner ``agent`` (``"pi2"``, ``"pibb"`` or ``"cmaes"``) with validated ``options``.

    Args:
        agent: learner name.
        initial_mean: ``[n]`` start action.
        rollouts: rollouts per update.
        rng: the learner's random generator.
        options: fields of the learner's config dataclass (a misspelt name is a ``ValueError``).
        time_weights: ``[T, n]`` activation of each action dimension per control step (PI² only).
    """
    if agent not in LEARNERS:
        raise ValueError(f"agent: expected one of {sorted(LEARNERS)}, got {agent!r}")
    cls, config_cls = LEARNERS[agent]
    config = from_options(config_cls, options, agent)
    if cls is PI2:
        if time_weights is None:
            raise ValueError("time_weights: PI² needs the activation of each parameter per control step")
        return PI2(initial_mean, rollouts, rng, time_weights, config)
    return cls(initial_mean, rollouts, rng, config)
