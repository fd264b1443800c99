"""The interface every episodic learner implements: ask for rollouts, tell their results, checkpoint.

A learner searches the environment's action space ``[-1, 1]^n`` (``a = 0`` is the imitation fit). One
update is one ``ask`` (``K`` actions to try) followed by one ``tell`` (their results). The learner
minimises the episode cost ``J = -return``; :class:`EpisodeBatch` carries the results.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["EpisodeBatch", "Learner", "LearnerInputs", "check_state_like", "cost_to_go", "cost_weights", "ridge_hat"]


@dataclass(frozen=True)
class EpisodeBatch:
    """Results of ``K`` episodes.

    Attributes:
        actions: ``[K, n]`` the actions that were executed.
        returns: ``[K]`` episode returns (higher is better).
        cost_traces: ``[K, T]`` per-control-step costs (the part of ``-return`` spread over time).
        valid: ``[K]`` whether each episode was simulated (an invalid plan gets a penalty instead).
        seeds: ``[K]`` the reset seeds.
        metrics: ``{key: [K]}`` the task's metrics (its contract's, e.g. the wiping task's coverage; NaN where an
            episode has none).
        success: ``[K]`` the env's ``info["is_success"]``, or None where the env does not give it.
        failures: ``[K]`` the success criteria each episode missed (``""`` for a success), or None where the env
            does not name them.
    """

    actions: np.ndarray
    returns: np.ndarray
    cost_traces: np.ndarray
    valid: np.ndarray
    seeds: np.ndarray
    metrics: Mapping[str, np.ndarray] = field(default_factory=dict)
    success: np.ndarray | None = None
    failures: np.ndarray | None = None

    @property
    def size(self) -> int:
        """Number of episodes ``K``."""
        return int(self.returns.size)

    @property
    def costs(self) -> np.ndarray:
        """``[K]`` episode costs ``-return``."""
        return -self.returns


def cost_weights(costs: np.ndarray, h: float) -> np.ndarray:
    """PI²'s probability weighting ``P_k ∝ exp(-h (J_k - min J) / (max J - min J))``.

    Args:
        costs: ``[..., K]`` costs of K rollouts (the last axis is normalised).
        h: eliteness; 10 in Theodorou et al. 2010 and Stulp & Sigaud 2012.
    Returns:
        ``[..., K]`` weights that sum to 1 over the last axis (uniform where all costs are equal).
    """
    low = costs.min(axis=-1, keepdims=True)
    spread = costs.max(axis=-1, keepdims=True) - low
    scaled = np.divide(costs - low, spread, out=np.zeros_like(costs, dtype=np.float64), where=spread > 0)
    weights = np.exp(-h * scaled)
    return weights / weights.sum(axis=-1, keepdims=True)


def cost_to_go(costs: np.ndarray, traces: np.ndarray) -> np.ndarray:
    """``[N, T]`` the cost still to come from each control step on: the per-step costs ``traces [N, T]`` summed
    from that step to the end, plus the part of the episode costs ``costs [N]`` that the traces do not hold."""
    terminal = costs - traces.sum(axis=1)
    return np.cumsum(traces[:, ::-1], axis=1)[:, ::-1] + terminal[:, None]


def ridge_penalty(size: int, prior: float) -> np.ndarray:
    """``[size, size]`` the ridge penalty ``prior * I`` of regressors ``[1, φ]``, the constant column unpenalised."""
    penalty = prior * np.eye(size)
    penalty[0, 0] = 1e-9
    return penalty


def ridge_hat(x: np.ndarray, prior: float) -> np.ndarray:
    """``[N, N]`` hat matrix of a ridge regression on ``x [N, F+1]`` (the constant column unpenalised)."""
    return x @ np.linalg.solve(x.T @ x + ridge_penalty(x.shape[1], prior), x.T)


def check_state_like(value: Any, template: Any, path: str) -> None:
    """Raise ``ValueError`` naming ``path`` unless ``value`` has the structure of ``template``.

    Dicts need the same keys; arrays the same shape except along the first axis (which may grow, e.g. a
    history; an empty template array fixes no shape) and the same kind (float arrays finite); numbers,
    strings, bools, lists and Generators their own kind. List lengths and first-axis lengths are left to
    the owner's checks.
    """
    def fail(expected: str) -> None:
        raise ValueError(f"{path}: expected {expected}, got {type(value).__name__}")

    if template is None:
        return
    if isinstance(template, Mapping):
        if not isinstance(value, Mapping):
            fail("a mapping")
        missing, extra = sorted(set(template) - set(value)), sorted(set(value) - set(template))
        if missing or extra:
            raise ValueError(f"{path}: missing entries {missing}, unexpected entries {extra}")
        for key in template:
            check_state_like(value[key], template[key], f"{path}.{key}")
    elif isinstance(template, np.ndarray):
        if not isinstance(value, np.ndarray):
            fail("an array")
        shape_known = template.size > 0              # an empty template (e.g. a buffer not filled yet) fixes no shape
        if (shape_known and (value.ndim != template.ndim or value.shape[1:] != template.shape[1:])) \
                or (value.dtype.kind == "b") != (template.dtype.kind == "b") or value.dtype.kind not in "biuf":
            raise ValueError(f"{path}: expected an array of shape [*, {', '.join(map(str, template.shape[1:]))}] "
                             f"like {template.shape} ({template.dtype}), got shape {value.shape} ({value.dtype})")
        if value.dtype.kind == "f" and not np.all(np.isfinite(value)):
            raise ValueError(f"{path}: contains NaN or infinite values")
    elif isinstance(template, (bool, np.bool_)):
        if not isinstance(value, (bool, np.bool_)):
            fail("true or false")
    elif isinstance(template, (int, np.integer)):
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
            fail("an integer")
    elif isinstance(template, (float, np.floating)):
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
            fail("a number")
        if np.isfinite(template) and not np.isfinite(value):
            raise ValueError(f"{path}: expected a finite number, got {value}")
    elif isinstance(template, str):
        if not isinstance(value, str):
            fail("a string")
    elif isinstance(template, (list, tuple)):
        if not isinstance(value, (list, tuple)):
            fail("a list")
    elif isinstance(template, np.random.Generator) and not isinstance(value, np.random.Generator):
        fail("a numpy Generator")


@dataclass(frozen=True)
class LearnerInputs:
    """What the task gives a learner beyond its settings when it is built (see :meth:`Learner.build`).

    Attributes:
        name: the name the learner was registered under (one class may serve several, e.g. ``creps``, ``cpi2``).
        time_weights: ``[T, n]`` activation of each action dimension per control step (PI²), or None.
        space: the action layout and context standardisation
            (:class:`~rdmp_gym.agents.learners.contextual.SearchSpace`; the contextual learners, and the smooth
            exploration of the others), or None.
    """

    name: str = ""
    time_weights: np.ndarray | None = None
    space: Any = None


class Learner(ABC):
    """An episodic black-box learner over actions in ``[-1, 1]^n``.

    A learner joins the registry with :func:`rdmp_gym.agents.registry.register` in its own module; the
    training loop builds it with :meth:`build`.

    Args:
        initial_mean: ``[n]`` start of the search (0 = the imitation fit).
        rollouts: episodes per update ``K``.
        rng: the only source of randomness of the learner.
    """

    name: str = ""
    #: whether :meth:`ask` needs the rollouts' contexts (observations) and the policy depends on them
    uses_context: bool = False

    def __init__(self, initial_mean: np.ndarray, rollouts: int, rng: np.random.Generator) -> None:
        mean = np.array(initial_mean, dtype=np.float64)
        if mean.ndim != 1 or mean.size == 0 or not np.all(np.isfinite(mean)):
            raise ValueError(f"initial_mean: expected a finite 1-D array, got shape {mean.shape}")
        if np.any(np.abs(mean) > 1.0):
            raise ValueError("initial_mean: expected values in [-1, 1] (the action space)")
        if isinstance(rollouts, bool) or not isinstance(rollouts, (int, np.integer)) or rollouts < 2:
            raise ValueError(f"rollouts: expected an int >= 2, got {rollouts!r}")
        if not isinstance(rng, np.random.Generator):
            raise TypeError(f"rng: expected a numpy.random.Generator, got {type(rng).__name__}")
        self.rollouts = int(rollouts)
        self.rng = rng
        self.updates = 0
        self._mean = mean

    @classmethod
    def build(cls, initial_mean: np.ndarray, rollouts: int, rng: np.random.Generator, config: Any,
              inputs: LearnerInputs) -> Learner:
        """The learner for a run: its settings ``config`` and what it needs of the task (``inputs``).

        The default passes only the settings; learners that need the time weights or the action layout
        override it and say so in a ``ValueError`` when it is missing.
        """
        return cls(initial_mean, rollouts, rng, config)

    @property
    def n_params(self) -> int:
        """Dimension ``n`` of the action space."""
        return int(self._mean.size)

    @property
    def mean(self) -> np.ndarray:
        """``[n]`` the current policy (the centre of the search distribution), a copy."""
        return self._mean.copy()

    @property
    @abstractmethod
    def exploration(self) -> float:
        """The current exploration level: the mean standard deviation of the search distribution."""

    @abstractmethod
    def ask(self, observations: np.ndarray | None = None) -> np.ndarray:
        """``[K, n]`` actions in ``[-1, 1]`` to evaluate next; ``observations [K, o]`` are the rollouts'
        contexts (used by contextual learners, ignored by the others)."""

    def policy_actions(self, observations: np.ndarray) -> np.ndarray:
        """``[E, n]`` the policy's action for contexts ``observations [E, o]`` (here: the mean for all)."""
        return np.repeat(self._mean[None], len(observations), axis=0)

    def choose_seeds(self, fresh: np.ndarray) -> np.ndarray:
        """``[K]`` the reset seeds of the next rollouts, given ``fresh [K]`` new ones (here: those); a contextual
        learner may replace some with the seeds of earlier training contexts to revisit them."""
        return fresh

    @abstractmethod
    def _update(self, batch: EpisodeBatch) -> None:
        """Update the search distribution from the results of the asked actions."""

    def tell(self, batch: EpisodeBatch) -> None:
        """Receive the results of the actions returned by the last :meth:`ask`, and update."""
        if batch.actions.shape != (self.rollouts, self.n_params):
            raise ValueError(f"batch.actions: expected shape {(self.rollouts, self.n_params)}, "
                             f"got {batch.actions.shape}")
        if not np.all(np.isfinite(batch.returns)):
            raise ValueError("batch.returns: contains NaN or infinite values")
        self._update(batch)
        self.updates += 1

    def state_dict(self) -> dict[str, Any]:
        """Everything needed to continue exactly where the learner is.

        A tree of dicts, lists, numbers, strings, numpy arrays and RNG states (``bit_generator.state``
        dicts or Generators), which :mod:`rdmp_gym.agents.state_files` stores as JSON + ``.npz`` without
        pickle. A learner adds its own entries through :meth:`_extra_state`.
        """
        return {"name": self.name, "mean": self._mean.copy(), "updates": self.updates,
                "rng": self.rng.bit_generator.state, **self._extra_state()}

    def load_state_dict(self, state: Mapping[str, Any]) -> None:
        """Restore a state written by :meth:`state_dict` (same learner type and dimension).

        The state is checked against this learner's own :meth:`state_dict` before anything is changed:
        the same keys, the same kinds of values, arrays of the same dimensionality (finite floats);
        a mismatch is a ``ValueError`` naming the entry.
        """
        if not isinstance(state, Mapping):
            raise TypeError(f"state: expected a mapping, got {type(state).__name__}")
        if state.get("name") != self.name:
            raise ValueError(f"state: written by learner {state.get('name')!r}, this is {self.name!r}")
        check_state_like(state, self.state_dict(), "state")
        mean = np.asarray(state["mean"], dtype=np.float64)
        if mean.shape != self._mean.shape or np.any(np.abs(mean) > 1.0):
            raise ValueError(f"state.mean: expected shape {self._mean.shape} in [-1, 1], got shape {mean.shape}")
        if state["updates"] < 0:
            raise ValueError(f"state.updates: expected a count >= 0, got {state['updates']}")
        previous = (self._mean, self.updates, self.rng.bit_generator.state)
        try:
            self.rng.bit_generator.state = state["rng"]
        except (TypeError, ValueError, KeyError) as error:
            raise ValueError(f"state.rng: not a valid {type(self.rng.bit_generator).__name__} state ({error})") \
                from error
        self._mean, self.updates = mean.copy(), int(state["updates"])
        try:
            self._load_extra_state(state)
        except BaseException:
            self._mean, self.updates, self.rng.bit_generator.state = previous
            raise

    @abstractmethod
    def _extra_state(self) -> dict[str, Any]:
        """Learner-specific state for :meth:`state_dict`."""

    @abstractmethod
    def _load_extra_state(self, state: dict[str, Any]) -> None:
        """Restore what :meth:`_extra_state` wrote."""
