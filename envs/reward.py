"""Episode reward of a wipe: named terms, each with a per-control-step cost trace.

The return is ``sum(terms.values())`` and the per-step cost trace sums (up to rounding) to its
negative, so episodic learners (PI², which needs a cost-to-go per time step) and SB3 see the same
objective. Terms (weights in :class:`RewardWeights`, all dimensionless and O(1)):

- ``coverage``: ``+w`` x wiped dirty cells / dirty cells, charged at the last step (a terminal cost):
  which cells a step wipes first depends on what earlier steps already wiped, so a per-step "newly
  wiped" cost would blame the later steps of a rollout that wipes well early on, and PI²'s per-step
  weighting learned measurably worse with it (benchmarks/bench_agents.py);
- ``force``: ``+w`` x mean over the periodic phase of ``exp(-((F - F*) / sigma)^2 / 2)``, the closeness
  of the sponge–table normal force F to its target F*;
- ``excess_force``: ``-w`` x mean over all steps of ``min(1, max(0, F - F_max) / F_max)``;
- ``contact_loss``: ``-w`` x fraction of the periodic phase with F below the contact threshold;
- ``joint_limit``: ``-w`` x fraction of steps with a joint within the margin of its limit;
- ``arm_collision``: ``-w`` x fraction of steps with an arm (non-sponge) contact with the environment;
- ``invalid``: ``-w`` x (1 + severity in [0, 1]) for a parameter vector rejected before simulation;
- ``unstable``: ``-w`` if the simulation diverged (then the episode ends at that step).
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from .wiping import WipeTrace

__all__ = ["TERMS", "RewardSettings", "RewardWeights", "invalid_reward", "wipe_reward"]

TERMS = ("coverage", "force", "excess_force", "contact_loss", "joint_limit", "arm_collision",
         "invalid", "unstable")


@dataclass(frozen=True)
class RewardWeights:
    """Weight of each reward term (see the module docstring); all >= 0."""

    coverage: float = 1.0
    force: float = 0.2
    excess_force: float = 1.0
    contact_loss: float = 0.5
    joint_limit: float = 0.5
    arm_collision: float = 1.0
    invalid: float = 1.0
    unstable: float = 1.0

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if not (isinstance(value, (int, float, np.floating)) and np.isfinite(value) and value >= 0):
                raise ValueError(f"reward_weights: {f.name} must be a finite number >= 0, got {value!r}")

    @classmethod
    def from_mapping(cls, weights: dict | None) -> RewardWeights:
        """Defaults overridden by a ``{term: weight}`` mapping (unknown terms raise ValueError)."""
        if weights is None:
            return cls()
        if isinstance(weights, cls):
            return weights
        unknown = set(weights) - {f.name for f in fields(cls)}
        if unknown:
            raise ValueError(f"reward_weights: unknown term(s) {sorted(unknown)}; expected some of {list(TERMS)}")
        return cls(**{k: float(v) for k, v in weights.items()})


@dataclass(frozen=True)
class RewardSettings:
    """Force targets of the reward.

    Attributes:
        target_force: the normal force F* to hold while wiping (N).
        force_sigma: width of the force-closeness score (N).
        max_force: forces above this are penalised (N) (the top of the wiping band).
        contact_threshold: a normal force below this counts as no contact (N).
    """

    target_force: float = 18.0
    force_sigma: float = 6.0
    max_force: float = 60.0
    contact_threshold: float = 1.0


def _terms(parts: dict[str, np.ndarray]) -> tuple[dict[str, float], np.ndarray]:
    """Cost traces per term ``[T]`` -> (reward terms = -sum of each trace, total cost trace ``[T]``)."""
    terms = {name: -float(np.sum(parts[name])) + 0.0 for name in TERMS}
    trace = np.sum([parts[name] for name in TERMS], axis=0)
    return terms, trace


def wipe_reward(trace: WipeTrace, periodic: np.ndarray, n_cells: int, settings: RewardSettings,
                weights: RewardWeights) -> tuple[dict[str, float], np.ndarray]:
    """Reward terms and the per-step cost trace ``[T]`` of a simulated wipe.

    Args:
        trace: the simulation record (``T`` control steps; only the first ``trace.steps`` count).
        periodic: mask ``[T]`` of the steps in the periodic (wiping) phase.
        n_cells: number of dirty cells.
    """
    count = len(trace.contact_force)
    live = np.arange(count) < trace.steps
    force = trace.contact_force
    per = periodic & live
    n_per = max(1, int(np.count_nonzero(periodic)))
    parts = {name: np.zeros(count) for name in TERMS}
    parts["coverage"][max(trace.steps, 1) - 1] = -weights.coverage * float(np.sum(trace.new_cells)) / max(1, n_cells)
    score = np.exp(-0.5 * ((force - settings.target_force) / settings.force_sigma) ** 2)
    parts["force"] = -weights.force * np.where(per, score, 0.0) / n_per
    excess = np.minimum(1.0, np.maximum(0.0, force - settings.max_force) / settings.max_force)
    parts["excess_force"] = weights.excess_force * np.where(live, excess, 0.0) / count
    parts["contact_loss"] = weights.contact_loss * (per & (force < settings.contact_threshold)) / n_per
    parts["joint_limit"] = weights.joint_limit * (trace.at_limit & live) / count
    parts["arm_collision"] = weights.arm_collision * (trace.arm_contact & live) / count
    if trace.unstable:
        # The rest of the episode is lost: it counts as if the sponge lost contact from here on.
        lost = periodic & ~live
        parts["contact_loss"] = parts["contact_loss"] + weights.contact_loss * lost / n_per
        parts["unstable"][trace.steps - 1] = weights.unstable
    return _terms(parts)


def invalid_reward(severity: float, count: int, weights: RewardWeights) -> tuple[dict[str, float], np.ndarray]:
    """Terms and a uniform cost trace ``[count]`` for a parameter vector rejected before simulation."""
    severity = float(np.clip(severity, 0.0, 1.0))
    parts = {name: np.zeros(count) for name in TERMS}
    parts["invalid"] = np.full(count, weights.invalid * (1.0 + severity) / count)
    return _terms(parts)
