"""``bbrl``'s settings, apart from :mod:`rdmp_gym.agents.learners.bbrl` so that declaring and checking them does
not import torch (the learner's module is imported when a run builds it)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from rdmp_gym.validation import check_choice, check_range

from ..registry import register
from .contextual import ContextualSettings

__all__ = ["BASELINES", "CREDITS", "LINEAR_FITS", "STEP_WEIGHTINGS", "VALUE_RIDGE", "BBRLConfig"]

CREDITS = ("step", "episode")
BASELINES = ("ridge", "network")
LINEAR_FITS = ("adam", "ridge")
STEP_WEIGHTINGS = ("activation", "remaining")
#: ridge of the context baselines of the cost (and cost-to-go)
VALUE_RIDGE = 1.0


@dataclass(frozen=True)
class BBRLConfig(ContextualSettings):
    """Settings of :class:`~rdmp_gym.agents.learners.bbrl.BBRL` (beyond :class:`ContextualSettings`, whose
    ``epsilon`` bounds the trust region: the largest mean KL divergence of one update; 1.0, the step ``cpi2`` takes:
    with 0.2 the noise in the weighted means of a hundred or more action dimensions fills the bound, and a value that
    matters moves at their pace).

    Attributes:
        rough: share of independent (not smooth) exploration in the correlation.
        rank: columns of the learned low-rank covariance factor ``U`` (0 = none; it starts at small random values).
        hidden: width of the two hidden layers of the mean network.
        credit: ``"step"`` (per-step credit from the cost trace, where the task gives one) or ``"episode"``.
        step_weighting: how per-step credit averages each dimension's per-step weights over time: by its
            activation (``"activation"``) or by its activation times the steps that remain, ``T - t``
            (``"remaining"``, PI²'s averaging of its per-step updates, which ``cpi2`` uses).
        epochs: Adam steps per update.
        learning_rate: Adam's step size.
        baseline: ``"ridge"`` (a ridge regression of the cost on the context over the reused samples) or
            ``"network"`` (an MLP of the cost-to-go, fitted to the last ``history`` batches, then the ridge).
        history: batches the ``"network"`` baseline is fitted to (those before the ``reuse`` batches it judges).
        value_epochs: Adam steps of the baseline network per update.
        context_scale: the network also gives each context a scale ``s(s)`` of the exploration
            (``Sigma(s) = s(s)^2 Sigma``, 1 at the start), fitted with the covariance, so that the exploration can
            stay wide where wide samples pay and narrow where they do not.
        linear: the mean has a linear part ``W s`` beside the network (zero at the start): it extrapolates to
            contexts beyond those seen (the largest patches) as a linear policy does, the network bends it where
            the cost needs it (a cup).
        linear_fit: how the linear part is fitted: ``"adam"`` (a map ``W s`` in the network's whitened
            coordinates, fitted with the network) or ``"ridge"`` (an affine map ``b + B s`` of the action, fitted in
            closed form by each action dimension's weighted ridge regression on its per-step credit weights, as
            ``cpi2`` fits its gains; the network then fits what the affine map leaves; both inside the trust region).
        linear_prior: ``"ridge"`` only: the ridge pulling the gains ``B`` towards their previous value
            (``cpi2``'s ``gain_prior``; the offset ``b`` is free).
        antithetic: mirrored sampling: the rollouts come in pairs ``mu(s) + e``, ``mu(s) - e`` on the same
            context ``s``, and each sample is judged against its pair's mean cost (and cost-to-go) instead of the
            ridge regression on the context; needs an even number of rollouts.

    The policy sets every action dimension; the ridge of its context baselines is :data:`VALUE_RIDGE`.
    """

    epsilon: float = 1.0
    min_sigma: float = 0.01
    rough: float = 0.1
    rank: int = 0
    hidden: int = 64
    credit: str = "step"
    step_weighting: str = "activation"
    epochs: int = 10
    learning_rate: float = 1e-2
    baseline: str = "ridge"
    history: int = 20
    value_epochs: int = 50
    antithetic: bool = False
    context_scale: bool = False
    linear: bool = False
    linear_fit: str = "adam"
    linear_prior: float = 10.0

    def __post_init__(self) -> None:
        super().__post_init__()
        check_range(self.rough, "rough", 0.0, 1.0, low_open=True)
        check_range(self.rank, "rank", 0, None)
        check_range(self.hidden, "hidden", 1, None)
        check_choice(self.credit, "credit", CREDITS)
        check_range(self.epochs, "epochs", 1, None)
        check_range(self.learning_rate, "learning_rate", 0.0, None, low_open=True)
        check_choice(self.baseline, "baseline", BASELINES)
        check_range(self.history, "history", 1, None)
        check_range(self.value_epochs, "value_epochs", 1, None)
        check_choice(self.linear_fit, "linear_fit", LINEAR_FITS)
        check_choice(self.step_weighting, "step_weighting", STEP_WEIGHTINGS)
        check_range(self.linear_prior, "linear_prior", 0.0, None, low_open=True)
        if self.linear_fit == "ridge" and not self.linear:
            raise ValueError("linear_fit: 'ridge' fits the linear part of the mean, which needs linear=True")

    @classmethod
    def fixed_values(cls) -> dict[str, Any]:
        return {"groups": (), "value_ridge": VALUE_RIDGE, "replay": 0.0, "replay_temperature": 0.3,
                "replay_size": 100}


register("bbrl", BBRLConfig, "rdmp_gym.agents.learners.bbrl:BBRL", uses_context=True)
