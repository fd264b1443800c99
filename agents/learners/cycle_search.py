"""Cycle-by-cycle policy search: each cycle's DMP parameters chosen from what is observed at its start.

The policy runs on a task's cycle-level face (:mod:`rdmp_gym.envs.cycle_env`): at the start of cycle ``c`` it
observes ``o_c`` (the context, the task's state, the cycle's place in the episode) and acts

    a_c = clip(W_c x(o_c) + ε_c, -1, 1),        x(o) = [1, (o - centre) / scale]        ([n], [F + 1])

one linear map ``W_c [n, F + 1]`` per cycle, ``ε_c = √ρ ε + √(1 - ρ) ε'_c`` smooth exploration in the DMP's
weights (:class:`~rdmp_gym.agents.learners.smooth_exploration.SmoothNoise`, standard deviation ``sigma``): a part
``ρ`` (``shared``) of its variance is one draw for the whole episode (a change that helps in every cycle is then
seen in the whole episode's cost, not diluted over the cycles' independent draws), the rest is the cycle's own. From
the
second cycle on, the dimensions that act in no control step of the cycle (a transient's weights once it has ended,
:meth:`~rdmp_gym.envs.rhythmic_env.RhythmicTaskEnv.action_time_weights`) keep the previous cycle's value, so the
cycle changes only what it can change.

**Credit where each draw acts.** A draw is judged by the cost that follows where it acts: the shared draw by the
whole episode's cost ``J``, cycle ``c``'s own draw by ``S_c = J - Σ_{t < t_c} cost(t)`` (the episode cost less what
was spent before the cycle started; the part of ``J`` the cost trace does not spread over time counts in every
cycle). Its samples (this batch and the ``reuse - 1`` before it) are weighted by ``P ∝ exp(-(S - b) / η)`` over a
ridge baseline ``b`` of the context (the first cycle's observation: it depends on no draw), with the temperature
``η`` set so that ``KL(P || uniform) = epsilon`` (the update's trust region). The shared draws move every cycle's map
alike: by the weighted ridge fit of the draws on the context's regressors less the same fit with uniform weights
(PI²'s reweighted noise, with gains on the context). Cycle ``c``'s own draws move its map alone, by the same fit on
``x(o_c)``; its gains on the task's state (the feedback) keep a share ``feedback_keep`` of their value before the
update's change is added (0 by default: each update's own, not accumulated). With ``pooled`` the cycles after the
first share one map, fitted to all their own draws. Measured on ``ArmarWipe-v3``: with every cycle fitted by its own
credit (shared draws included) the cycles' maps drifted apart, each difference a hand-over, and the policy lost the
imitation's smoothness within 400 episodes. The exploration decays geometrically,
``sigma <- max(min_sigma, decay sigma)``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.optimize import brentq

from rdmp_gym.validation import check_range

from ..config import Settings
from .base import ridge_hat
from .credit import weighted_ridge
from .smooth_exploration import SmoothNoise

__all__ = ["CycleBatch", "CycleSearch", "CycleSearchConfig", "act_with", "stack_cycles", "trust_region_weights"]


@dataclass(frozen=True)
class CycleSearchConfig(Settings):
    """Settings of :class:`CycleSearch`.

    Attributes:
        sigma: initial exploration standard deviation (action units, the mean over the weights).
        length: correlation length of the exploration in neighbouring DMP weights (0 = independent).
        epsilon: the trust region, ``KL(P || uniform)`` of each cycle's sample weights.
        shared: the part of the exploration's variance that the cycles of an episode share (0: independent
            cycles, 1: one draw per episode).
        reuse: batches (this one and earlier ones) whose samples enter each update.
        gain_prior: the ridge of the gains in each update's fits of the draws (and of the baselines).
        decay: factor applied to sigma after every update.
        min_sigma: exploration floor.
        pooled: the cycles after the first share one map, fitted to the own draws of all of them (each judged by its
            own cycle's credit), instead of one map per cycle: the cycles then differ only where what they observe
            differs, and every cycle's samples inform the one map.
        feedback_keep: the share of the gains on the task's state (the feedback) that an update keeps before it adds
            its own change (0: each update's gains are its own; 1: they accumulate as the other gains do).
    """

    sigma: float = 0.3
    length: float = 5.0
    epsilon: float = 1.0
    shared: float = 0.7
    reuse: int = 3
    gain_prior: float = 1.0
    decay: float = 0.96
    min_sigma: float = 0.03
    pooled: bool = False
    feedback_keep: float = 0.0

    def __post_init__(self) -> None:
        check_range(self.sigma, "sigma", 0.0, 1.0, low_open=True)
        check_range(self.length, "length", 0.0, None)
        check_range(self.epsilon, "epsilon", 0.0, None, low_open=True)
        check_range(self.shared, "shared", 0.0, 1.0)
        check_range(self.reuse, "reuse", 1, None)
        check_range(self.gain_prior, "gain_prior", 0.0, None, low_open=True)
        check_range(self.decay, "decay", 0.0, 1.0, low_open=True)
        check_range(self.min_sigma, "min_sigma", 0.0, self.sigma)
        check_range(self.feedback_keep, "feedback_keep", 0.0, 1.0)


@dataclass(frozen=True)
class CycleBatch:
    """Results of ``N`` exploring episodes on a cycle-level face with ``C`` cycles.

    Attributes:
        observations: ``[N, C, o]`` each cycle's observation (NaN for cycles an episode did not reach).
        costs: ``[N]`` episode costs ``-return``.
        spent: ``[N, C]`` the cost trace summed before each cycle's start (0 for the first cycle).
        shared, own: ``[N, n]``, ``[N, C, n]`` the exploration's parts as drawn (:meth:`CycleSearch.exploration`),
            scaled as executed.
    """

    observations: np.ndarray
    costs: np.ndarray
    spent: np.ndarray
    shared: np.ndarray
    own: np.ndarray

    def __post_init__(self) -> None:
        size, cycles = self.observations.shape[:2]
        if (self.costs.shape != (size,) or self.spent.shape != (size, cycles) or self.own.shape[:2] != (size, cycles)
                or self.shared.shape != (size, self.own.shape[2])):
            raise ValueError(f"batch: expected observations [N, C, o], costs [N], spent [N, C], shared [N, n], own "
                             f"[N, C, n]; got {self.observations.shape}, {self.costs.shape}, {self.spent.shape}, "
                             f"{self.shared.shape}, {self.own.shape}")
        if not np.all(np.isfinite(self.costs)):
            raise ValueError("batch.costs: contains NaN or infinite values")


def trust_region_weights(advantages: np.ndarray, epsilon: float) -> np.ndarray:
    """``[N]`` weights ``∝ exp(-A / η)`` of advantages ``[N]`` (lower is better) with ``η`` such that
    ``KL(P || uniform) = epsilon`` (uniform where the advantages are all equal, or where even ``η -> 0`` stays
    within the bound: then the best sample takes nearly all weight)."""
    spread = advantages.max() - advantages.min()
    if not spread > 0:
        return np.full(advantages.size, 1.0 / advantages.size)
    scaled = (advantages - advantages.min()) / spread

    def weights(log_temperature: float) -> np.ndarray:
        logits = -scaled / np.exp(log_temperature)
        p = np.exp(logits - logits.max())
        return p / p.sum()

    def excess(log_temperature: float) -> float:
        p = weights(log_temperature)
        return float(np.sum(p * np.log(np.maximum(p * p.size, 1e-300)))) - epsilon

    low, high = np.log(1e-4), np.log(1e4)
    if excess(low) <= 0:
        return weights(low)
    return weights(brentq(excess, low, high, xtol=1e-6) if excess(high) < 0 else high)


class CycleSearch:
    """The cycle-by-cycle policy and its search (see the module docstring).

    Args:
        n_actions: the cycle face's action size ``n``.
        context_size: the observation's first entries that are the context (the rest is the task's state).
        active: ``[C, n]`` whether each action dimension acts during each cycle.
        center, scale: ``[o]`` standardisation of the observation (scale 0: the entry is left out).
        blocks: the exploration's blocks (:func:`~rdmp_gym.agents.learners.smooth_exploration.block_layout`).
        config: the settings.
        rng: the only source of the exploration noise.
    """

    def __init__(self, n_actions: int, context_size: int, active: np.ndarray, center: np.ndarray,
                 scale: np.ndarray, blocks: list[tuple[slice, bool | None]], config: CycleSearchConfig,
                 rng: np.random.Generator):
        self.active = np.asarray(active, dtype=bool)
        if self.active.ndim != 2 or self.active.shape[1] != n_actions:
            raise ValueError(f"active: expected shape [C, {n_actions}], got {self.active.shape}")
        self.center, self.scale = np.asarray(center, dtype=np.float64), np.asarray(scale, dtype=np.float64)
        if self.center.shape != self.scale.shape or self.center.ndim != 1:
            raise ValueError(f"center, scale: expected two arrays [o], got {self.center.shape}, {self.scale.shape}")
        if not 0 <= context_size <= self.center.size:
            raise ValueError(f"context_size: expected 0 to {self.center.size}, got {context_size!r}")
        self.context_size = int(context_size)
        self.config, self.rng = config, rng
        self.noise = SmoothNoise(n_actions, blocks, config.length)
        self.sigma = config.sigma
        #: ``[C, n, F + 1]`` the policy: one linear map per cycle (0: the imitation in every cycle)
        self.maps = np.zeros((self.n_cycles, n_actions, self.center.size + 1))
        self.updates = 0
        self._history: list[CycleBatch] = []

    @property
    def n_cycles(self) -> int:
        """Cycles ``C`` of an episode."""
        return self.active.shape[0]

    def features(self, observation: np.ndarray) -> np.ndarray:
        """``[F + 1]`` the regressors ``x(o)`` of an observation ``[o]``."""
        return _features(observation, self.center, self.scale)

    def exploration(self, count: int) -> tuple[np.ndarray, np.ndarray]:
        """The exploration of ``count`` episodes as executed: ``(shared [count, n], own [count, C, n])``, each cycle's
        draw ``shared + own[:, c]`` (the generator advances)."""
        scales = np.full(self.noise.n_blocks, self.sigma)
        own = self.noise.sample(scales, count * self.n_cycles, self.rng).reshape(count, self.n_cycles, -1)
        shared = self.noise.sample(scales, count, self.rng)
        return np.sqrt(self.config.shared) * shared, np.sqrt(1.0 - self.config.shared) * own

    def act(self, cycle: int, observation: np.ndarray, previous: np.ndarray | None, noise: np.ndarray | None = None
            ) -> np.ndarray:
        """``[n]`` the action of cycle ``cycle`` at ``observation [o]`` (with ``noise [n]`` where given); the
        dimensions that do not act in the cycle keep ``previous [n]`` (the last cycle's action)."""
        return act_with(self._view(), cycle, observation, previous, noise)

    def update(self, batch: CycleBatch) -> None:
        """Move the maps by the credit of the draws of ``batch`` and the ``reuse - 1`` batches before it."""
        self._history = [*self._history, batch][-self.config.reuse:]
        observations = np.concatenate([b.observations for b in self._history])
        shared = np.concatenate([b.shared for b in self._history])                           # [N, n]
        own = np.concatenate([b.own for b in self._history])                                 # [N, C, n]
        to_go = np.concatenate([b.costs[:, None] - b.spent for b in self._history])          # [N, C]
        contexts = np.stack([self.features(o) for o in observations[:, 0]])
        baseline = ridge_hat(contexts, self.config.gain_prior * len(contexts))   # shrinks as that many samples
        common = self._reweighted(contexts, shared, to_go[:, 0] - baseline @ to_go[:, 0])     # [n, F + 1]
        groups = [[0], list(range(1, self.n_cycles))] if self.config.pooled else [[c] for c in range(self.n_cycles)]
        for group in filter(None, groups):
            change = common + self._own_change(group, observations, own, to_go, contexts)
            for cycle in group:
                updated = self.maps[cycle] + change
                feedback = slice(1 + self.context_size, None)
                updated[:, feedback] = self.config.feedback_keep * self.maps[cycle][:, feedback] + change[:, feedback]
                self.maps[cycle] = np.where(self.active[cycle][:, None], updated, self.maps[cycle])
        self.sigma = max(self.config.min_sigma, self.config.decay * self.sigma)
        self.updates += 1

    def _own_change(self, group: list[int], observations: np.ndarray, own: np.ndarray, to_go: np.ndarray,
                    contexts: np.ndarray) -> np.ndarray:
        """``[n, F + 1]`` the change of the map the cycles of ``group`` share, from their own draws ``own [N, C, n]``
        at their observations ``[N, C, o]``, each judged by its cycle's cost-to-go ``to_go [N, C]`` over a ridge
        baseline on the context (``contexts [N, F + 1]``) within the trust region (every cycle of the group counts
        alike)."""
        rows, weights, uniform = [], [], []
        for cycle in group:
            reached = np.all(np.isfinite(observations[:, cycle]), axis=1)
            if reached.sum() < 2:
                continue
            to_go_c = to_go[reached, cycle]
            hat = ridge_hat(contexts[reached], self.config.gain_prior * int(reached.sum()))
            rows.append((np.stack([self.features(o) for o in observations[reached, cycle]]), own[reached, cycle]))
            weights.append(trust_region_weights(to_go_c - hat @ to_go_c, self.config.epsilon))
            uniform.append(np.full(int(reached.sum()), 1.0 / reached.sum()))
        if not rows:
            return np.zeros_like(self.maps[0])
        x, draws = np.concatenate([r[0] for r in rows]), np.concatenate([r[1] for r in rows])
        both = np.stack([np.concatenate(weights), np.concatenate(uniform)]) / len(rows)
        by_cost, even = weighted_ridge(x, both, draws, np.zeros((draws.shape[1], x.shape[1])), self.config.gain_prior)
        return by_cost - even

    def _reweighted(self, x: np.ndarray, draws: np.ndarray, advantages: np.ndarray) -> np.ndarray:
        """``[n, F + 1]`` the fit of ``draws [N, n]`` on ``x [N, F + 1]`` weighted by the advantages ``[N]`` (within
        the trust region) less the same fit with uniform weights."""
        weights = np.stack([trust_region_weights(advantages, self.config.epsilon), np.full(len(x), 1.0 / len(x))])
        by_cost, uniform = weighted_ridge(x, weights, draws, np.zeros((draws.shape[1], x.shape[1])),
                                          self.config.gain_prior)
        return by_cost - uniform

    def state_dict(self) -> dict[str, Any]:
        """What continues the search exactly: the maps, the exploration, the generator, the standardisation."""
        return {"maps": self.maps.copy(), "sigma": self.sigma, "updates": self.updates,
                "rng": self.rng.bit_generator.state, "center": self.center.copy(), "scale": self.scale.copy()}

    def policy(self) -> dict[str, np.ndarray]:
        """The policy without its search: ``{"maps", "center", "scale", "active"}`` (what :func:`act_with` runs),
        copies."""
        return {key: value.copy() for key, value in self._view().items()}

    def _view(self) -> dict[str, np.ndarray]:
        return {"maps": self.maps, "center": self.center, "scale": self.scale, "active": self.active}


#: the standardised observation is clipped to this many standard deviations: the standardisation comes from the
#: imitation's episodes, in which the task's state (e.g. the tool's offset from its path) varies little, and an
#: exploring episode's state may lie outside it (measured on ``ArmarWipe-v3``: up to 6 standard deviations), where a
#: gain's effect stays bounded
FEATURE_CLIP = 3.0


def _features(observation: np.ndarray, center: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """``[F + 1]``: ``[1, (o - center) / scale]`` clipped to ``±FEATURE_CLIP``, 0 where the scale is 0."""
    scaled = np.divide(observation - center, scale, out=np.zeros_like(center), where=scale > 0)
    return np.r_[1.0, np.clip(scaled, -FEATURE_CLIP, FEATURE_CLIP)]


def act_with(policy: dict[str, np.ndarray], cycle: int, observation: np.ndarray, previous: np.ndarray | None,
             noise: np.ndarray | None = None) -> np.ndarray:
    """``[n]`` the action of a policy ``{"maps" [C, n, F + 1], "center", "scale" [o], "active" [C, n]}`` (see
    :meth:`CycleSearch.act`)."""
    action = policy["maps"][cycle] @ _features(observation, policy["center"], policy["scale"])
    action = np.clip(action if noise is None else action + noise, -1.0, 1.0)
    if cycle > 0 and previous is not None:
        action = np.where(policy["active"][cycle], action, previous)
    return action


def stack_cycles(rows: Sequence[np.ndarray], cycles: int, size: int) -> np.ndarray:
    """``[C, size]`` the rows ``[c, size]`` of the cycles an episode reached, NaN for the rest."""
    out = np.full((cycles, size), np.nan)
    if len(rows):
        out[: len(rows)] = np.stack(rows)
    return out
