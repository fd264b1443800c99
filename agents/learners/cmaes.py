"""CMA-ES (Hansen) through the ``cma`` package's ask/tell interface, on the action box ``[-1, 1]^n``.

The population size is the number of rollouts per update. The box is handled by ``cma``'s
``BoundTransform`` (``bounds="transform"``) or ``BoundPenalty`` (``bounds="penalty"``). ``cma`` draws its
normal samples through the ``randn`` option, which is fed from the learner's Generator, so the run is
reproducible and the pickled strategy (with the Generator inside) restores exactly.
"""

from __future__ import annotations

import math
import pickle
from dataclasses import dataclass
from typing import Any

import cma
import numpy as np

from ..options import check_choice, check_range
from .base import EpisodeBatch, Learner

__all__ = ["CMAES", "CMAESConfig"]

BOUND_MODES = ("transform", "penalty")


@dataclass(frozen=True)
class CMAESConfig:
    """CMA-ES settings.

    Attributes:
        sigma: initial step size in action units.
        bounds: ``"transform"`` or ``"penalty"`` handling of the ``[-1, 1]`` box.
        diagonal: learn only a diagonal covariance (separable CMA-ES; faster in high dimension).
    """

    sigma: float = 0.6
    bounds: str = "transform"
    diagonal: bool = False

    def __post_init__(self) -> None:
        check_range(self.sigma, "cmaes.sigma", 0.0, None, low_open=True)
        check_choice(self.bounds, "cmaes.bounds", BOUND_MODES)


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
    """

    name = "cmaes"

    def __init__(self, initial_mean: np.ndarray, rollouts: int, rng: np.random.Generator,
                 config: CMAESConfig | None = None) -> None:
        super().__init__(initial_mean, rollouts, rng)
        self.config = config or CMAESConfig()
        handler = cma.BoundTransform if self.config.bounds == "transform" else cma.BoundPenalty
        options = {"popsize": self.rollouts, "bounds": [-1.0, 1.0], "BoundaryHandler": handler,
                   "randn": _GeneratorNormal(self.rng), "seed": math.nan, "CMA_diagonal": self.config.diagonal,
                   "verbose": -9, "verb_disp": 0, "verb_log": 0, "tolflatfitness": 10**9,
                   "tolfun": 0.0, "tolfunhist": 0.0, "tolx": 0.0, "tolstagnation": 10**9,
                   "maxiter": 10**9, "maxfevals": 10**12}
        self.strategy = cma.CMAEvolutionStrategy(self._mean.copy(), self.config.sigma, options)
        self._pending: list[np.ndarray] | None = None

    @property
    def exploration(self) -> float:
        return float(np.mean(self.strategy.sigma * np.sqrt(self.strategy.sm.variances)))

    def ask(self, observations: np.ndarray | None = None) -> np.ndarray:
        self._pending = self.strategy.ask()
        return np.clip(np.array(self._pending, dtype=np.float64), -1.0, 1.0)

    def _update(self, batch: EpisodeBatch) -> None:
        if self._pending is None:
            raise RuntimeError("tell: call ask() first")
        asked = np.clip(np.array(self._pending), -1.0, 1.0)
        if not np.array_equal(asked, batch.actions):
            raise ValueError("batch.actions: not the actions returned by the last ask()")
        self.strategy.tell(self._pending, batch.costs.tolist())
        self._pending = None
        self._mean = np.clip(np.asarray(self.strategy.result.xfavorite, dtype=np.float64), -1.0, 1.0)

    def _extra_state(self) -> dict[str, Any]:
        if self._pending is not None:
            raise RuntimeError("state_dict: an ask() is waiting for its tell()")
        return {"strategy": pickle.dumps(self.strategy)}

    def _load_extra_state(self, state: dict[str, Any]) -> None:
        strategy = pickle.loads(state["strategy"])
        if strategy.N != self.n_params:
            raise ValueError(f"state: strategy has dimension {strategy.N}, expected {self.n_params}")
        self.strategy = strategy
        self.rng = strategy.opts["randn"].rng  # the strategy samples from the Generator pickled with it
        self._pending = None
