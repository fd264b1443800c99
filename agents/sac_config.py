"""SAC settings, apart from ``rdmp_gym.agents.sb3`` so that checking them does not import torch.

SAC on the one-step task (a contextual bandit): every episode is one transition that terminates, so
the critic learns ``Q(context, action) = r`` and ``gamma`` plays no role. One update = ``rollouts``
environment steps from the current policy (no uniformly random warm-up: ``learning_starts`` 0, since
random actions in ~250 dimensions are far from any wiping motion), then ``gradient_steps`` per step.
The squashed-Gaussian actor starts at the imitation (mean layer bias ``atanh(start)``) with
``std = sigma``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .options import check_range

__all__ = ["SACConfig"]


@dataclass(frozen=True)
class SACConfig:
    """SAC settings.

    Attributes:
        sigma: initial standard deviation of the (pre-squash) Gaussian policy.
        learning_rate: Adam step size (actor, critic, entropy coefficient).
        batch_size: replay minibatch size.
        gradient_steps: gradient steps per environment step.
        hidden: units in each of the two hidden layers (actor and critics).
        buffer_size: replay buffer capacity (episodes).
        length: correlation length of the exploration in neighbouring DMP weights: the policy acts on a latent
            vector mapped smoothly to the action (:mod:`rdmp_gym.agents.smooth_actions`); 0 = on the action itself.
    """

    sigma: float = 0.3
    learning_rate: float = 1e-3
    batch_size: int = 64
    gradient_steps: int = 1
    hidden: int = 64
    buffer_size: int = 100_000
    length: float = 0.0

    def __post_init__(self) -> None:
        check_range(self.sigma, "sac.sigma", 0.0, None, low_open=True)
        check_range(self.learning_rate, "sac.learning_rate", 0.0, 1.0, low_open=True)
        check_range(self.batch_size, "sac.batch_size", 1, None)
        check_range(self.gradient_steps, "sac.gradient_steps", 1, None)
        check_range(self.hidden, "sac.hidden", 1, None)
        check_range(self.buffer_size, "sac.buffer_size", 1, None)
        check_range(self.length, "sac.length", 0.0, math.inf, high_open=True)
