"""Episodic learners behind one ask/tell interface.

Shared-θ learners: PI² and CMA-ES. ``bbrl`` (:mod:`.bbrl`): a neural network from the raw context to a
Gaussian over the action, updated within a KL trust region; ``bbrl_segments`` (:mod:`.segment_bbrl`): the same
policy, each action dimension credited with the cost of the parts of the movement it acts in. Contextual learners
(:mod:`.contextual`, a linear-Gaussian policy θ = θ̄ + K·φ(s) with smooth exploration): ``creps`` (contextual
REPS), ``cpibb`` (contextual PI^BB), ``cpi2`` (contextual PI²); and the two baselines every table shows beside
them: ``amplitude`` (one θ over the 3 amplitude factors only) and ``random`` (contextual REPS fed random returns).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ..config import Settings
from ..registry import REGISTRY, agent_spec
from . import cmaes, contextual, pi2  # noqa: F401  (each declares its learners)
from .base import EpisodeBatch, Learner, LearnerInputs, cost_weights
from .bbrl_config import BBRLConfig
from .cmaes import CMAES, CMAESConfig
from .contextual import ContextualConfig, ContextualSearch, ContextualSettings, SearchSpace
from .contextual import policy_from_state as contextual_policy_from_state
from .pi2 import PI2, PI2Config
from .segment_bbrl_config import SegmentBBRLConfig

__all__ = [
    "CMAES",
    "CONTEXTUAL",
    "LEARNERS",
    "PI2",
    "BBRLConfig",
    "CMAESConfig",
    "ContextualConfig",
    "ContextualSearch",
    "ContextualSettings",
    "EpisodeBatch",
    "Learner",
    "LearnerInputs",
    "PI2Config",
    "SearchSpace",
    "SegmentBBRLConfig",
    "cost_weights",
    "make_learner",
    "policy_from_state",
]

#: the ask/tell learners, as their modules declared them (:func:`rdmp_gym.agents.registry.register`)
LEARNERS = {name: spec for name, spec in REGISTRY.items() if spec.kind == "learner"}

#: the contextual learners (their policy depends on the context; they need a :class:`SearchSpace`)
CONTEXTUAL = tuple(name for name, spec in LEARNERS.items() if spec.uses_context)


def make_learner(agent: str, initial_mean: np.ndarray, rollouts: int, rng: np.random.Generator,
                 options: Mapping[str, Any] | Settings | None = None, time_weights: np.ndarray | None = None,
                 space: SearchSpace | None = None) -> Learner:
    """Create the learner ``agent`` (a key of :data:`LEARNERS`) with validated ``options``.

    Args:
        agent: learner name.
        initial_mean: ``[n]`` start action.
        rollouts: rollouts per update.
        rng: the learner's random generator.
        options: the learner's settings, or a mapping of their fields (a misspelt name is a ``ValueError``).
        time_weights: ``[T, n]`` activation of each action dimension per control step (PI² only).
        space: action layout and context standardisation (the contextual learners; PI² and CMA-ES
            with ``length > 0``, their smooth exploration).
    """
    spec = agent_spec(agent)
    if spec.kind != "learner":
        raise ValueError(f"agent: expected one of {sorted(LEARNERS)}, got {agent!r}")
    config = options if isinstance(options, spec.config) else spec.config.from_dict(options, agent)
    return spec.load().build(initial_mean, rollouts, rng, config, LearnerInputs(agent, time_weights, space))


def policy_from_state(state: Mapping[str, Any], observations: np.ndarray) -> np.ndarray:
    """``[E, n]`` the policy actions of a learner's state (``state_dict()``) for observations ``[E, o]``: a learner
    without a context policy (CMA-ES, PI²) acts with its mean in every context."""
    if not agent_spec(state["name"]).uses_context:
        return np.repeat(np.asarray(state["mean"], dtype=np.float64)[None], len(observations), axis=0)
    if state.get("name") in ("bbrl", "bbrl_segments"):
        from .bbrl import bbrl_policy_actions  # torch, only for a bbrl state

        return bbrl_policy_actions(state, observations)
    return contextual_policy_from_state(state, observations)
