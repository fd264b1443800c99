"""Settings of the stable-baselines3 agents, apart from :mod:`rdmp_gym.agents.sb3` so that declaring and checking
them does not import torch.

**PPO.** PPO as a contextual bandit, one step per episode, and why these settings:

* one update = one PPO iteration of ``rollouts`` episodes: ``n_steps = rollouts / n`` per env, ``n`` the
  largest divisor of ``rollouts`` not above the ``envs`` setting (2). ``n`` is a setting, not the worker
  count, so PPO's numbers do not depend on ``--workers`` (which only decides whether the ``n`` envs
  step in this process or in ``n`` subprocesses);
* every episode terminates after its single step (``terminated=True``), so the advantage is
  ``r - V(context)`` and ``gamma``/``gae_lambda`` play no role;
* the observation is the env's context; the policy is a Gaussian whose mean starts at the imitation
  (``action_net`` bias = start action, weights scaled by 0.01 as SB3 does) with ``std = sigma``, the same
  initial exploration as the black-box learners;
* ``batch_size`` 0 means the whole update is one minibatch; ``n_epochs`` passes over it;
* the learning rate (3e-2) is far above SB3's 3e-4 default because a budget of a few hundred episodes
  gives only tens of updates; it was the best of 3e-3, 1e-2 and 3e-2 on the wiping task (one seed).
  On ``ArmarWipe-v2`` the task's default is 3e-3 (its learner defaults,
  ``rdmp_gym.envs.tasks.wiping.versions.LEARNER_DEFAULTS``):
  with smooth actions at 3e-2 one of 2 seeds' policy mean ran far outside the action box (98 % of its latent means
  beyond ±1, up to 85), every weight was executed at a face and the path had 2.7x the imitation's jerk; 3e-3 gave
  test success 0.47 and 1.34x (2 seeds x 2000 episodes);
* ``length`` (5 on ``ArmarWipe-v2``) makes the policy act on a latent vector that a fixed smooth map turns
  into the action (``agents/sb3_smooth_actions.py``): the exploration and the learned mean are smooth along the
  movement; with ``length`` 0 (v1) the ~250 weights get independent noise and the learned mean was 37x as
  jerky as the imitation on v2;
* ``target_kl`` (0.05) stops an update's epochs once the policy has moved that far (SB3 stops at
  1.5 x target_kl): with ~250 action dimensions and that learning rate, the probability ratio of later
  epochs otherwise overflowed and the policy became NaN (seen once in the benchmark).

``sigma`` 0.6 (like the black-box learners' default) was the better of 0.3 and 0.6 for every learner.

**SAC.** SAC settings, apart from ``rdmp_gym.agents.sb3`` so that checking them does not import torch.

On the one-step task (a contextual bandit): every episode is one transition that terminates, so
the critic learns ``Q(context, action) = r`` and ``gamma`` plays no role. One update = ``rollouts``
environment steps from the current policy (no uniformly random warm-up: ``learning_starts`` 0, since
random actions in ~250 dimensions are far from any wiping motion), then ``gradient_steps`` per step.
The squashed-Gaussian actor starts at the imitation (mean layer bias ``atanh(start)``) with
``std = sigma``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from rdmp_gym.validation import check_range

from .config import Settings
from .registry import register

__all__ = ["PPOConfig", "SACConfig", "SB3Settings"]


@dataclass(frozen=True)
class SB3Settings(Settings):
    """Settings PPO and SAC share.

    Attributes:
        sigma: initial standard deviation of the Gaussian policy (action units; SAC's before the squash).
        learning_rate: Adam step size.
        batch_size: minibatch size.
        hidden: units in each of the two hidden layers of the networks.
        length: correlation length of the exploration in neighbouring DMP weights: the policy acts on a latent
            vector mapped smoothly to the action (:mod:`rdmp_gym.agents.sb3_smooth_actions`); 0 = on the action itself.
    """

    sigma: float = 0.6
    learning_rate: float = 3e-2
    batch_size: int = 0
    hidden: int = 64
    length: float = 0.0

    def __post_init__(self) -> None:
        check_range(self.sigma, f"{self.label}.sigma", 0.0, None, low_open=True)
        check_range(self.learning_rate, f"{self.label}.learning_rate", 0.0, 1.0, low_open=True)
        check_range(self.batch_size, f"{self.label}.batch_size", 0, None)
        check_range(self.hidden, f"{self.label}.hidden", 1, None)
        check_range(self.length, f"{self.label}.length", 0.0, math.inf, high_open=True)


@dataclass(frozen=True)
class PPOConfig(SB3Settings):
    """PPO settings (beyond :class:`SB3Settings`; ``batch_size`` 0 = all episodes of the update).

    Attributes:
        n_epochs: passes over each update's episodes.
        clip_range: PPO ratio clipping.
        ent_coef: entropy bonus.
        target_kl: early stop of an update's epochs at this approximate KL divergence; 0 = never.
        envs: parallel envs of the vector env (at most; the largest divisor of ``rollouts`` not above it).
        tensorboard: write SB3's training statistics to ``<run>/tensorboard`` (needs the ``tensorboard`` extra).
    """

    label = "ppo"
    n_epochs: int = 10
    clip_range: float = 0.2
    ent_coef: float = 0.0
    target_kl: float = 0.05
    envs: int = 2
    tensorboard: bool = False

    def __post_init__(self) -> None:
        super().__post_init__()
        check_range(self.n_epochs, "ppo.n_epochs", 1, None)
        check_range(self.clip_range, "ppo.clip_range", 0.0, 1.0, low_open=True)
        check_range(self.target_kl, "ppo.target_kl", 0.0, None)
        check_range(self.ent_coef, "ppo.ent_coef", 0.0, None)
        check_range(self.envs, "ppo.envs", 1, None)


@dataclass(frozen=True)
class SACConfig(SB3Settings):
    """SAC settings (beyond :class:`SB3Settings`).

    Attributes:
        gradient_steps: gradient steps per environment step.
        buffer_size: replay buffer capacity (episodes).
    """

    label = "sac"
    sigma: float = 0.3
    learning_rate: float = 1e-3
    batch_size: int = 64
    gradient_steps: int = 1
    buffer_size: int = 100_000

    def __post_init__(self) -> None:
        super().__post_init__()
        check_range(self.batch_size, "sac.batch_size", 1, None)
        check_range(self.gradient_steps, "sac.gradient_steps", 1, None)
        check_range(self.buffer_size, "sac.buffer_size", 1, None)


register("ppo", PPOConfig, "rdmp_gym.agents.sb3:PPOAgent", kind="sb3")
register("sac", SACConfig, "rdmp_gym.agents.sb3:SACAgent", kind="sb3")
