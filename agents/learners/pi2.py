"""PI² for DMPs (Theodorou, Buchli, Schaal 2010), in its episodic form with constant noise per rollout.

Per update: ``K`` rollouts ``a_k = a + eps_k``, ``eps_k ~ N(0, sigma² I)`` in action space (the env
maps actions affinely onto the selected DMP parameter groups). From each rollout's per-step costs
``c_k(t)`` (``T`` control steps) and its total cost ``J_k = -return_k``:

* cost-to-go ``S_k(t) = sum_{t' >= t} c_k(t') + (J_k - sum_t c_k(t))``; the part of ``J_k`` that the
  env does not spread over time (e.g. the wiping task's coverage, known only at the end) counts at every step, so
  ``S_k(0) = J_k``;
* ``P_k(t) ∝ exp(-h (S_k(t) - min_k S(t)) / (max_k S(t) - min_k S(t)))`` for every step (h = 10);
* per-step update ``d(t) = sum_k P_k(t) eps_k`` (``[T, n]``);
* per-parameter time average with weights ``(T - t) * activation_i(t)``, where ``activation_i(t)`` in
  [0, 1] (``[T, n]``, from the env's ``action_time_weights()``) says how active parameter i's basis
  function is at step t: a transient weight is credited with what followed while its basis function
  was active, a periodic weight with the periodic phase. A parameter that is never active is not moved.

Exploration decays geometrically, ``sigma <- max(min_sigma, decay * sigma)``, after every update.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from rdmp_gym.validation import check_range

from ..config import Settings
from ..registry import register
from .base import EpisodeBatch, Learner, LearnerInputs
from .credit import remaining_steps, step_credit
from .smooth_exploration import exploration_factor

__all__ = ["PI2", "PI2Config"]


@dataclass(frozen=True)
class PI2Config(Settings):
    """PI² settings.

    Attributes:
        sigma: initial exploration standard deviation in action units.
        h: eliteness of the cost weighting.
        decay: factor applied to sigma after every update (1 = no annealing).
        min_sigma: exploration floor.
        length: correlation length of the exploration in neighbouring DMP weights (0 = independent noise, as in
            the original PI²; > 0 needs the action layout, :func:`rdmp_gym.agents.learners.make_learner`'s ``space``).
    """

    sigma: float = 0.6
    h: float = 10.0
    decay: float = 0.95
    min_sigma: float = 0.02
    length: float = 0.0

    def __post_init__(self) -> None:
        check_range(self.sigma, "pi2.sigma", 0.0, None, low_open=True)
        check_range(self.h, "pi2.h", 0.0, None, low_open=True)
        check_range(self.decay, "pi2.decay", 0.0, 1.0, low_open=True)
        check_range(self.min_sigma, "pi2.min_sigma", 0.0, self.sigma)
        check_range(self.length, "pi2.length", 0.0, None)


class PI2(Learner):
    """PI² with per-time-step cost-to-go weighting and basis-activation time averaging.

    Args:
        initial_mean: ``[n]`` start action.
        rollouts: rollouts per update ``K``.
        rng: source of the exploration noise.
        time_weights: ``[T, n]`` activation of each action dimension at each control step, in [0, 1].
        config: the settings.
        factor: ``[n, n]`` shape of the exploration noise (``sigma · factor ε``; default the identity), e.g.
            :func:`~rdmp_gym.agents.learners.smooth_exploration.smooth_factor`.
    """

    name = "pi2"

    def __init__(self, initial_mean: np.ndarray, rollouts: int, rng: np.random.Generator,
                 time_weights: np.ndarray, config: PI2Config | None = None, factor: np.ndarray | None = None) -> None:
        super().__init__(initial_mean, rollouts, rng)
        self.config = config or PI2Config()
        weights = np.asarray(time_weights, dtype=np.float64)
        if weights.ndim != 2 or weights.shape[1] != self.n_params or weights.shape[0] < 1:
            raise ValueError(f"time_weights: expected shape [T, {self.n_params}], got {weights.shape}")
        if not np.all(np.isfinite(weights)) or weights.min() < 0.0 or weights.max() > 1.0:
            raise ValueError("time_weights: expected finite values in [0, 1]")
        self._step_weights = remaining_steps(weights)                                          # [T, n]
        self.sigma = self.config.sigma
        self.factor = np.eye(self.n_params) if factor is None else np.asarray(factor, dtype=np.float64)
        if self.factor.shape != (self.n_params, self.n_params):
            raise ValueError(f"factor: expected shape ({self.n_params}, {self.n_params}), got {self.factor.shape}")

    @classmethod
    def build(cls, initial_mean: np.ndarray, rollouts: int, rng: np.random.Generator, config: PI2Config,
              inputs: LearnerInputs) -> PI2:
        """PI² needs the time weights, and with ``length > 0`` the action layout."""
        if inputs.time_weights is None:
            raise ValueError("time_weights: PI² needs the activation of each parameter per control step")
        factor = exploration_factor(np.asarray(initial_mean).size, config.length, inputs.space, inputs.name)
        return cls(initial_mean, rollouts, rng, inputs.time_weights, config, factor)

    @property
    def exploration(self) -> float:
        return float(self.sigma)

    def ask(self, observations: np.ndarray | None = None) -> np.ndarray:
        noise = self.sigma * self.rng.standard_normal((self.rollouts, self.n_params)) @ self.factor.T
        return np.clip(self._mean + noise, -1.0, 1.0)

    def _update(self, batch: EpisodeBatch) -> None:
        traces = batch.cost_traces
        steps = self._step_weights.shape[0]
        if traces.shape != (batch.size, steps):
            raise ValueError(f"batch.cost_traces: expected shape {(batch.size, steps)} (one cost per "
                             f"control step), got {traces.shape}")
        noise = batch.actions - self._mean                                        # [K, n]
        delta = step_credit(batch.costs, traces, self.config.h, self._step_weights, np.zeros(self.n_params),
                            per_step=lambda weights: weights @ noise)              # [n]: P(t) @ ε averaged
        self._mean = np.clip(self._mean + delta, -1.0, 1.0)
        self.sigma = max(self.config.min_sigma, self.config.decay * self.sigma)

    def _extra_state(self) -> dict[str, Any]:
        return {"sigma": self.sigma}

    def _load_extra_state(self, state: dict[str, Any]) -> None:
        self.sigma = float(state["sigma"])


register("pi2", PI2Config, PI2)
