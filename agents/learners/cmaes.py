"""CMA-ES (Hansen) through the ``cma`` package's ask/tell interface, on the action box ``[-1, 1]^n``.

The population size is the number of rollouts per update. The box is handled by ``cma``'s
``BoundTransform``, and the covariance is full (not separable). ``cma`` draws its
normal samples through the ``randn`` option, which is fed from the learner's Generator, so the run is
reproducible. The strategy is not stored as an object: the state holds the start (mean and RNG state)
and the costs told so far ``[U, K]``, and loading replays the ``U`` generations, which restores the
strategy exactly (and checks that the replay reaches the stored RNG state and mean).

With ``length > 0`` the search runs in smooth coordinates ``z``: ``a = clip(a0 + L z)``, ``L`` the factor of the
correlation of neighbouring DMP weights (:func:`.smooth.smooth_factor`), so the first generations explore
smooth paths and the covariance CMA-ES learns is a correction of that shape; the box is then kept by clipping.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import cma
import numpy as np

from rdmp_gym.validation import check_range

from ..config import Settings
from ..registry import register
from .base import EpisodeBatch, Learner, LearnerInputs
from .smooth_exploration import exploration_factor

__all__ = ["CMAES", "CMAESConfig"]


@dataclass(frozen=True)
class CMAESConfig(Settings):
    """CMA-ES settings.

    Attributes:
        sigma: initial step size in action units.
        length: correlation length of the exploration in neighbouring weights (0 = CMA-ES's isotropic start).
    """

    sigma: float = 0.6
    length: float = 0.0

    def __post_init__(self) -> None:
        check_range(self.sigma, "cmaes.sigma", 0.0, None, low_open=True)
        check_range(self.length, "cmaes.length", 0.0, None)

    @classmethod
    def fixed_values(cls) -> dict[str, Any]:
        return {"bounds": "transform", "diagonal": False}


class _GeneratorNormal:
    """``randn(*shape)`` drawn from a numpy Generator (what ``cma``'s ``randn`` option expects)."""

    def __init__(self, rng: np.random.Generator) -> None:
        self.rng = rng

    def __call__(self, *shape: int) -> np.ndarray:
        return self.rng.standard_normal(shape)


class CMAES(Learner):
    """CMA-ES over actions; one generation per update.

    Args:
        initial_mean: ``[n]`` start action.
        rollouts: population size ``K``.
        rng: source of the samples (handed to ``cma`` via its ``randn`` option).
        config: the settings.
        factor: ``[n, n]`` the smooth factor ``L`` (with ``config.length > 0``), else None.
    """

    name = "cmaes"

    def __init__(self, initial_mean: np.ndarray, rollouts: int, rng: np.random.Generator,
                 config: CMAESConfig | None = None, factor: np.ndarray | None = None) -> None:
        super().__init__(initial_mean, rollouts, rng)
        self.config = config or CMAESConfig()
        if factor is not None and np.shape(factor) != (self.n_params, self.n_params):
            raise ValueError(f"factor: expected shape [{self.n_params}, {self.n_params}], got {np.shape(factor)}")
        self.factor = None if factor is None else np.asarray(factor, dtype=np.float64)
        self._start_rng = self.rng.bit_generator.state
        self._start_mean = self._mean.copy()
        self._costs: list[np.ndarray] = []
        self.strategy = self._new_strategy()
        self._pending: list[np.ndarray] | None = None

    def _new_strategy(self) -> cma.CMAEvolutionStrategy:
        smooth = self.factor is not None
        options = {"popsize": self.rollouts, "bounds": [None, None] if smooth else [-1.0, 1.0],
                   "BoundaryHandler": None if smooth else cma.BoundTransform,
                   "randn": _GeneratorNormal(self.rng), "seed": math.nan, "CMA_diagonal": False,
                   "verbose": -9, "verb_disp": 0, "verb_log": 0, "tolflatfitness": 10**9,
                   "tolfun": 0.0, "tolfunhist": 0.0, "tolx": 0.0, "tolstagnation": 10**9,
                   "maxiter": 10**9, "maxfevals": 10**12}
        start = np.zeros(self.n_params) if smooth else self._start_mean.copy()
        return cma.CMAEvolutionStrategy(start, self.config.sigma, options)

    def _actions(self, points: Any) -> np.ndarray:
        """``[K, n]`` (or ``[n]``) the actions of CMA-ES's points (the smooth coordinates mapped back), in the box."""
        x = np.asarray(points, dtype=np.float64)
        if self.factor is not None:
            x = self._start_mean + x @ self.factor.T
        return np.clip(x, -1.0, 1.0)

    @classmethod
    def build(cls, initial_mean: np.ndarray, rollouts: int, rng: np.random.Generator, config: CMAESConfig,
              inputs: LearnerInputs) -> CMAES:
        """With ``length > 0`` the smooth exploration needs the action layout (``inputs.space``)."""
        factor = exploration_factor(np.asarray(initial_mean).size, config.length, inputs.space, inputs.name)
        return cls(initial_mean, rollouts, rng, config, factor)

    @property
    def exploration(self) -> float:
        return float(np.mean(self.strategy.sigma * np.sqrt(self.strategy.sm.variances)))

    def ask(self, observations: np.ndarray | None = None) -> np.ndarray:
        self._pending = self.strategy.ask()
        return self._actions(self._pending)

    def _update(self, batch: EpisodeBatch) -> None:
        if self._pending is None:
            raise RuntimeError("tell: call ask() first")
        if not np.array_equal(self._actions(self._pending), batch.actions):
            raise ValueError("batch.actions: not the actions returned by the last ask()")
        self.strategy.tell(self._pending, batch.costs.tolist())
        self._costs.append(np.array(batch.costs, dtype=np.float64))
        self._pending = None
        self._mean = self._actions(self.strategy.result.xfavorite)

    def _extra_state(self) -> dict[str, Any]:
        if self._pending is not None:
            raise RuntimeError("state_dict: an ask() is waiting for its tell()")
        costs = np.array(self._costs, dtype=np.float64).reshape(len(self._costs), self.rollouts)
        return {"start_mean": self._start_mean.copy(), "start_rng": self._start_rng, "costs": costs}

    def _load_extra_state(self, state: dict[str, Any]) -> None:
        costs = np.asarray(state["costs"], dtype=np.float64)
        start = np.asarray(state["start_mean"], dtype=np.float64)
        if costs.shape != (self.updates, self.rollouts) or start.shape != self._mean.shape:
            raise ValueError(f"state: costs {costs.shape} and start_mean {start.shape}, expected "
                             f"{(self.updates, self.rollouts)} and {self._mean.shape}")
        target_rng, target_mean = self.rng.bit_generator.state, self._mean.copy()
        self._start_mean, self._start_rng = start, state["start_rng"]
        self.rng.bit_generator.state = self._start_rng
        self.strategy = self._new_strategy()
        for row in costs:
            self.strategy.tell(self.strategy.ask(), row.tolist())
        self._costs = list(costs)
        self._pending = None
        self._mean = self._actions(self.strategy.result.xfavorite)
        if self.rng.bit_generator.state != target_rng or not np.array_equal(self._mean, target_mean):
            raise ValueError("state: replaying the stored CMA-ES generations does not reach the stored mean and "
                             "RNG state (the state was altered or written by another cma version)")


register("cmaes", CMAESConfig, CMAES)
