"""Episodic learners behind one ask/tell interface.

Shared-θ learners: PI², PI^BB and CMA-ES. ``bbrl`` (:mod:`.bbrl`): a neural network from the raw context to
a Gaussian over the action, updated within a KL trust region. Contextual learners (:mod:`.contextual`, a linear-Gaussian
policy θ = θ̄ + K·φ(s) with smooth exploration): ``creps`` (contextual REPS), ``cpibb`` (contextual
PI^BB), ``cpi2`` (contextual PI²); and the two baselines every table shows beside them: ``amplitude``
(one θ over the 3 amplitude factors only) and ``random`` (contextual REPS fed random returns).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ..options import from_options
from .base import EpisodeBatch, Learner, cost_weights
from .bbrl import BBRL, BBRLConfig, bbrl_policy_actions
from .cmaes import CMAES, CMAESConfig
from .contextual import (
    AmplitudeConfig,
    ContextualConfig,
    ContextualSearch,
    CPI2Config,
    CPIBBConfig,
    CREPSConfig,
    RandomReturnConfig,
    SearchSpace,
)
from .contextual import policy_from_state as contextual_policy_from_state
from .pi2 import PI2, PI2Config
from .pibb import PIBB, PIBBConfig
from .smooth import smooth_factor

__all__ = [
    "BBRL",
    "CMAES",
    "CONTEXTUAL",
    "LEARNERS",
    "PI2",
    "PIBB",
    "BBRLConfig",
    "CMAESConfig",
    "ContextualConfig",
    "ContextualSearch",
    "EpisodeBatch",
    "Learner",
    "PI2Config",
    "PIBBConfig",
    "SearchSpace",
    "bbrl_policy_actions",
    "cost_weights",
    "make_learner",
    "policy_from_state",
]

LEARNERS: dict[str, tuple[type[Learner], type]] = {
    "pi2": (PI2, PI2Config),
    "pibb": (PIBB, PIBBConfig),
    "cmaes": (CMAES, CMAESConfig),
    "creps": (ContextualSearch, CREPSConfig),
    "cpibb": (ContextualSearch, CPIBBConfig),
    "cpi2": (ContextualSearch, CPI2Config),
    "amplitude": (ContextualSearch, AmplitudeConfig),
    "random": (ContextualSearch, RandomReturnConfig),
    "bbrl": (BBRL, BBRLConfig),
}

#: the contextual learners (their policy depends on the context; they need a :class:`SearchSpace`)
CONTEXTUAL = tuple(name for name, (cls, _) in LEARNERS.items() if cls.uses_context)


def make_learner(agent: str, initial_mean: np.ndarray, rollouts: int, rng: np.random.Generator,
                 options: Mapping[str, Any] | None = None, time_weights: np.ndarray | None = None,
                 space: SearchSpace | None = None) -> Learner:
    """Create the learner ``agent`` (a key of :data:`LEARNERS`) with validated ``options``.

    Args:
        agent: learner name.
        initial_mean: ``[n]`` start action.
        rollouts: rollouts per update.
        rng: the learner's random generator.
        options: fields of the learner's config dataclass (a misspelt name is a ``ValueError``).
        time_weights: ``[T, n]`` activation of each action dimension per control step (PI² only).
        space: action layout and context standardisation (the contextual learners; PI², PI^BB and CMA-ES
            with ``length > 0``, their smooth exploration).
    """
    if agent not in LEARNERS:
        raise ValueError(f"agent: expected one of {sorted(LEARNERS)}, got {agent!r}")
    cls, config_cls = LEARNERS[agent]
    config = from_options(config_cls, options, agent)
    factor = None
    if getattr(config, "length", 0.0) > 0 and cls in (PI2, PIBB, CMAES):
        if space is None:
            raise ValueError(f"space: {agent} with length > 0 (smooth exploration) needs the action layout")
        factor = smooth_factor(np.asarray(initial_mean).size, space.slices, space.n_dims, config.length)
    if cls is PI2:
        if time_weights is None:
            raise ValueError("time_weights: PI² needs the activation of each parameter per control step")
        return PI2(initial_mean, rollouts, rng, time_weights, config, factor)
    if cls is PIBB:
        return PIBB(initial_mean, rollouts, rng, config, factor)
    if cls is CMAES:
        return CMAES(initial_mean, rollouts, rng, config, factor)
    if cls.uses_context and space is None:
        raise ValueError(f"space: {agent} needs the action layout and context standardisation (SearchSpace)")
    if cls is ContextualSearch:
        return ContextualSearch(initial_mean, rollouts, rng, space, config, name=agent)
    if cls is BBRL:
        return BBRL(initial_mean, rollouts, rng, space, config)
    return cls(initial_mean, rollouts, rng, config)


def policy_from_state(state: Mapping[str, Any], observations: np.ndarray) -> np.ndarray:
    """``[E, n]`` the policy actions of a contextual learner's state (``state_dict()``) for observations ``[E, o]``."""
    if state.get("name") == BBRL.name:
        return bbrl_policy_actions(state, observations)
    return contextual_policy_from_state(state, observations)
