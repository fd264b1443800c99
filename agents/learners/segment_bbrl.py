"""``bbrl_segments``: ``bbrl`` that credits each part of the movement with the cost incurred while it acts.

One number per episode cannot tell which part of a path went wrong: the hand grazes the cup for a few control
steps, and every weight of the primitive is blamed alike. Here the episode's per-step cost ``c_k(t)`` is split into
``M`` equal segments of the control steps, ``C_kj = sum_{t in j} c_k(t)`` (what the trace does not hold is booked in
the last segment), and:

1. a **critic** ``V_j(s)`` (an MLP of the raw, standardised context with one output per segment) is fitted to the
   segment costs of the ``history`` batches before the reused ones (off-policy: they came from earlier policies;
   it never sees the samples it judges); the segment advantage is what is left of ``C_kj - V_j(s_k)`` after a ridge
   regression on the context over the reused samples (the drift of the policy since the critic's data);
2. each action dimension ``i`` is **credited with the segments it acts in**: ``A_ki = (1 - b) sum_j w_ji A_kj +
   b sum_j A_kj``, ``w_ji`` the dimension's activation mass in segment ``j`` relative to its largest (the
   env's ``action_time_weights``: a periodic weight acts in every cycle, a transient weight in one or two
   segments, an anchor everywhere) and ``b`` the ``episode_share`` (costs judged once at the end, e.g. the wiping
   task's coverage, reach early dimensions through it);
3. ``bbrl``'s weighted maximum likelihood with per-dimension weights ``exp(-h A_ki / R_i)`` (normalised over the
   samples; ``R_i`` the range of dimension ``i``'s advantages as in PI², or with ``scale="common"`` the range of
   the episode advantages ``sum_j A_kj`` for every dimension, so that a dimension whose segments hardly differ
   between samples is left nearly where it is) and its KL trust region (:mod:`.bbrl`).

Nothing is task-specific: no groups, no per-group exploration factors, no features beyond the raw context. The
segments and the activation come from the primitive and the control steps alone.
"""

from __future__ import annotations

import numpy as np

from .base import cost_weights, ridge_hat
from .bbrl import BBRL, pair_hat
from .bbrl_config import VALUE_RIDGE
from .contextual import SearchSpace
from .segment_bbrl_config import SegmentBBRLConfig

__all__ = ["SegmentBBRL", "SegmentBBRLConfig", "common_scale_weights", "segment_activation", "segment_costs",
           "segment_starts", "segment_weights"]


def segment_starts(steps: int, segments: int) -> np.ndarray:
    """``[M]`` the first control step of each of ``M = min(segments, steps)`` near-equal parts of ``steps`` steps."""
    return np.unique(np.floor(np.linspace(0, steps, min(segments, steps) + 1)[:-1]).astype(np.int64))


def segment_costs(costs: np.ndarray, traces: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """``[N, M]`` the per-step costs ``traces [N, T]`` summed per segment (``starts [M]``); the part of the episode
    costs ``costs [N]`` that the traces do not hold is booked in the last segment. Rows sum to ``costs``."""
    parts = np.add.reduceat(np.asarray(traces, dtype=np.float64), starts, axis=1)
    parts[:, -1] += costs - traces.sum(axis=1)
    return parts


def segment_activation(time_weights: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """``[M, n]`` each dimension's activation mass per segment relative to its largest (1 in its most active
    segment), from ``time_weights [T, n]``; a dimension that never acts is credited with every segment (1)."""
    mass = np.add.reduceat(np.asarray(time_weights, dtype=np.float64), starts, axis=0)
    peak = mass.max(axis=0)
    return np.where(peak > 0, mass / np.where(peak > 0, peak, 1.0), 1.0)


def segment_weights(parts: np.ndarray, contexts: np.ndarray, activation: np.ndarray, h: float, ridge: float,
                    episode_share: float, predicted: np.ndarray | None = None, paired: bool = False,
                    common_scale: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Per-dimension and episode weights of ``N`` samples from their segment costs (steps 1-2 of the module
    docstring).

    Args:
        parts: ``[N, M]`` segment costs; contexts: ``[N, o]`` standardised contexts (the ridge's regressors).
        activation: ``[M, n]`` the dimensions' relative activation per segment (:func:`segment_activation`).
        h: eliteness; ridge: the ridge of the context regression; episode_share: ``b`` of the module docstring.
        predicted: ``[N, M]`` the critic's segment costs, subtracted first (None: 0).
        paired: antithetic pairs (rows 2i, 2i + 1): each pair's mean replaces the ridge.
        common_scale: one scale for every dimension (:func:`common_scale_weights`), else min-max per dimension.
    Returns:
        ``([n, N], [N])``, each row summing to 1 over the samples.
    """
    n_samples = len(parts)
    hat = pair_hat(n_samples) if paired else ridge_hat(np.c_[np.ones(n_samples), contexts], ridge)
    residual = parts - (0.0 if predicted is None else predicted)
    advantage = residual - hat @ residual                                             # [N, M]
    episode = advantage.sum(axis=1)                                                   # [N]
    per_dimension = (1.0 - episode_share) * (advantage @ activation) + episode_share * episode[:, None]
    weights = common_scale_weights(per_dimension.T, np.ptp(episode), h) if common_scale \
        else cost_weights(per_dimension.T, h)
    return weights, cost_weights(episode, h)


def common_scale_weights(advantages: np.ndarray, scale: float, h: float) -> np.ndarray:
    """``[n, N]`` weights ``exp(-h (A_ki - min_k A_ki) / scale)`` of the advantages ``[n, N]``, normalised per row.

    Unlike PI²'s per-row range, one ``scale`` (the episode advantage's range) for every dimension: a dimension
    whose segments hardly differ between the samples gets nearly uniform weights and stays where it is, instead
    of having its noise stretched to the full eliteness.
    """
    if scale <= 0:
        return np.full(advantages.shape, 1.0 / advantages.shape[1])
    weights = np.exp(-h * (advantages - advantages.min(axis=1, keepdims=True)) / scale)
    return weights / weights.sum(axis=1, keepdims=True)


class SegmentBBRL(BBRL):
    """``bbrl`` with per-segment credit and a segment critic (module docstring).

    Args:
        initial_mean: ``[n]`` start action (0 = the imitation).
        rollouts: episodes per update ``K``.
        rng: the only source of randomness.
        space: the action layout, the context standardisation and ``time_weights [T, n]`` (needed with
            ``credit="step"``).
        config: :class:`SegmentBBRLConfig`.
    """

    name = "bbrl_segments"

    def __init__(self, initial_mean: np.ndarray, rollouts: int, rng: np.random.Generator, space: SearchSpace,
                 config: SegmentBBRLConfig | None = None) -> None:
        config = config or SegmentBBRLConfig()
        if config.credit == "step" and space.time_weights is None:
            raise ValueError("space.time_weights: bbrl_segments credits each dimension with the segments it acts "
                             "in and needs the activation of each dimension per control step (or credit='episode')")
        super().__init__(initial_mean, rollouts, rng, space, config)
        #: ``[M]`` first control step of each segment and ``[M, n]`` the dimensions' activation per segment (None:
        #: episode credit)
        self.starts = None if self.time_weights is None else segment_starts(len(self.time_weights),
                                                                             self.config.segments)
        self.activation = None if self.starts is None else segment_activation(self.time_weights, self.starts)

    def _value_outputs(self) -> int:
        if self.time_weights is None:
            return 1
        return len(segment_starts(len(self.time_weights), self.config.segments))

    def _value_targets(self, batch: dict[str, np.ndarray]) -> np.ndarray:
        if self.starts is None:
            return super()._value_targets(batch)
        return segment_costs(batch["costs"], batch["traces"], self.starts)

    def _sample_weights(self, data: dict[str, np.ndarray],
                        predicted: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
        if self.starts is None:
            return super()._sample_weights(data, predicted)
        parts = segment_costs(data["costs"], data["traces"], self.starts)
        return segment_weights(parts, data["contexts"], self.activation, self.config.h, VALUE_RIDGE,
                               self.config.episode_share, predicted, paired=self.config.antithetic,
                               common_scale=self.config.scale == "common")
