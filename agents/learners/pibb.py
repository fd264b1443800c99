"""PI^BB (Stulp & Sigaud 2012): black-box reward-weighted averaging with one weighting per rollout.

Per update: ``K`` samples ``a_k ~ N(a, Sigma)``; ``P_k ∝ exp(-h (J_k - min J) / (max J - min J))``
(h = 10); the new mean is ``sum_k P_k a_k``. The covariance either decays (``Sigma <- decay² Sigma``)
or is adapted, ``Sigma <- (1 - lr) Sigma + lr sum_k P_k (a_k - a)(a_k - a)^T`` around the old mean,
with its eigenvalues kept at or above ``min_sigma²`` (the floor that prevents premature convergence).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from rdmp_gym.validation import check_choice, check_range

from ..config import Settings
from ..registry import register
from .base import EpisodeBatch, Learner, LearnerInputs, cost_weights
from .smooth_exploration import exploration_factor

__all__ = ["PIBB", "PIBBConfig"]

COVARIANCE_MODES = ("decay", "adaptation")


@dataclass(frozen=True)
class PIBBConfig(Settings):
    """PI^BB settings.

    Attributes:
        sigma: initial exploration standard deviation (``Sigma_0 = sigma² I``, or ``sigma² C`` with ``length``).
        h: eliteness of the cost weighting.
        covariance: ``"decay"`` or ``"adaptation"``.
        decay: standard-deviation factor per update (``"decay"`` mode).
        learning_rate: weight of the new estimate (``"adaptation"`` mode).
        min_sigma: floor of the standard deviation along every eigen-direction.
        length: correlation length of the initial exploration in neighbouring DMP weights (0 = independent; > 0
            needs the action layout, :func:`rdmp_gym.agents.learners.make_learner`'s ``space``).
    """

    sigma: float = 0.6
    h: float = 10.0
    covariance: str = "decay"
    decay: float = 0.95
    learning_rate: float = 0.5
    min_sigma: float = 0.02
    length: float = 0.0

    def __post_init__(self) -> None:
        check_range(self.sigma, "pibb.sigma", 0.0, None, low_open=True)
        check_range(self.h, "pibb.h", 0.0, None, low_open=True)
        check_choice(self.covariance, "pibb.covariance", COVARIANCE_MODES)
        check_range(self.decay, "pibb.decay", 0.0, 1.0, low_open=True)
        check_range(self.learning_rate, "pibb.learning_rate", 0.0, 1.0, low_open=True)
        check_range(self.min_sigma, "pibb.min_sigma", 0.0, self.sigma)
        check_range(self.length, "pibb.length", 0.0, None)


class PIBB(Learner):
    """PI^BB with covariance decay or covariance adaptation.

    Args:
        initial_mean: ``[n]`` start action.
        rollouts: samples per update ``K``.
        rng: source of the samples.
        config: the settings.
        factor: ``[n, n]`` shape of the initial exploration (``Sigma_0 = sigma² factor factorᵀ``; default the
            identity), e.g. :func:`~rdmp_gym.agents.learners.smooth_exploration.smooth_factor`.
    """

    name = "pibb"

    def __init__(self, initial_mean: np.ndarray, rollouts: int, rng: np.random.Generator,
                 config: PIBBConfig | None = None, factor: np.ndarray | None = None) -> None:
        super().__init__(initial_mean, rollouts, rng)
        self.config = config or PIBBConfig()
        shape = np.eye(self.n_params) if factor is None else np.asarray(factor, dtype=np.float64)
        if shape.shape != (self.n_params, self.n_params):
            raise ValueError(f"factor: expected shape ({self.n_params}, {self.n_params}), got {shape.shape}")
        self._factor = self.config.sigma * shape
        self.covariance = self._factor @ self._factor.T                  # [n, n]

    @classmethod
    def build(cls, initial_mean: np.ndarray, rollouts: int, rng: np.random.Generator, config: PIBBConfig,
              inputs: LearnerInputs) -> PIBB:
        """With ``length > 0`` the smooth exploration needs the action layout (``inputs.space``)."""
        factor = exploration_factor(np.asarray(initial_mean).size, config.length, inputs.space, inputs.name)
        return cls(initial_mean, rollouts, rng, config, factor)

    @property
    def exploration(self) -> float:
        return float(np.mean(np.sqrt(np.diag(self.covariance))))

    def ask(self, observations: np.ndarray | None = None) -> np.ndarray:
        noise = self.rng.standard_normal((self.rollouts, self.n_params)) @ self._factor.T
        return np.clip(self._mean + noise, -1.0, 1.0)

    def _update(self, batch: EpisodeBatch) -> None:
        weights = cost_weights(batch.costs, self.config.h)                     # [K]
        deviations = batch.actions - self._mean                                # [K, n]
        self._mean = np.clip(weights @ batch.actions, -1.0, 1.0)
        if self.config.covariance == "decay":
            self.covariance = self.config.decay**2 * self.covariance
        else:
            estimate = (weights[:, None] * deviations).T @ deviations           # [n, n]
            rate = self.config.learning_rate
            self.covariance = (1.0 - rate) * self.covariance + rate * estimate
        self._apply_floor()

    def _apply_floor(self) -> None:
        """Clamp the eigenvalues at ``min_sigma²`` and refresh the sampling factor."""
        values, vectors = np.linalg.eigh(0.5 * (self.covariance + self.covariance.T))
        values = np.maximum(values, self.config.min_sigma**2)
        self.covariance = (vectors * values) @ vectors.T
        self._factor = vectors * np.sqrt(values)

    def _extra_state(self) -> dict[str, Any]:
        return {"covariance": self.covariance.copy(), "factor": self._factor.copy()}

    def _load_extra_state(self, state: dict[str, Any]) -> None:
        covariance = np.array(state["covariance"], dtype=np.float64)
        factor = np.array(state["factor"], dtype=np.float64)
        if covariance.shape != self.covariance.shape or factor.shape != self._factor.shape:
            raise ValueError(f"state: covariance/factor shapes {covariance.shape}/{factor.shape}, expected "
                             f"{self.covariance.shape}")
        self.covariance, self._factor = covariance, factor


register("pibb", PIBBConfig, PIBB)
