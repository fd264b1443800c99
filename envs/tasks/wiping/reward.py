"""Episode reward of a wipe: named terms, each a per-control-step cost trace charged when it happens.

The return is ``sum(terms.values())`` and the per-step cost trace sums (up to rounding) to its
negative, so episodic learners (PI², which needs a cost-to-go per time step) and SB3 see the same
objective. Terms (weights in :class:`RewardWeights`, all dimensionless and O(1)):

- ``coverage``: ``+w`` x the fraction of the dirt removed (Preston wear, :mod:`rdmp_gym.envs.tasks.wiping.simulation`),
  charged at the last step: it is the state of the table at the end (terminal). A per-step
  "dirt removed now" cost would blame the later steps of a rollout that wipes well early on, and
  PI²'s per-step weighting learned measurably worse with it (benchmarks/bench_agents.py);
- ``force``: ``+w`` x mean over the periodic phase of ``exp(-((F - F*) / sigma)^2 / 2)``, the closeness
  of the sponge–table normal force F to its target F*, per step;
- ``excess_force``: ``-w`` x mean over all steps of ``min(1, max(0, F - F_max) / F_max)``, per step;
- ``contact_loss``: ``-w`` x fraction of the periodic phase with F below the contact threshold, per step;
- ``impact``: ``-w`` x ``min(1, max(0, F_peak - F_imp) / F_imp)``, F_peak the peak normal force within
  0.2 s of the first contact (sampled at every physics step), charged at the step of the peak;
- ``smoothness``: ``-w`` x ``ln(max(1, J / J_imitation))``, J the integrated squared jerk of the
  commanded sponge path and J_imitation that of the imitation (action 0) in the same context (in
  ``ArmarWipe-v2`` both per unit of integrated squared speed, :meth:`Smoothness.speed_normalised`, so that
  a larger or travelling pattern that is as smooth costs nothing); it is
  spread over the steps in proportion to the squared jerk at each. Weight 0.25: the smooth
  core's wide basis and soft spring low-pass random weights, so a uniformly
  random action is 7-25x as jerky as the imitation while its amplitude can still buy
  coverage; at 0.25 it costs 0.49-0.80 and such an action scores at least 0.49 below its smooth twin
  with the same coverage (20 contexts), while the smooth 6 cm lift over a cup (2.0x) costs 0.17
  against the cup's ~0.9;
- ``joint_accel``: ``-w`` x ``min(1, max(0, a_peak - a_max) / a_max)``, a_peak the peak commanded joint
  acceleration (a_max = 10 rad/s², ARMAR-III's joint limit), charged at the step of the peak;
- ``arm_collision``: ``-w`` x fraction of steps with a robot geom other than the sponge on the table;
- ``self_collision``: ``-w`` x fraction of steps with the arm touching the robot's torso, head or platform;
  in ``ArmarWipe-v2`` these two, ``joint_limit`` and ``joint_accel`` also cost ``RewardSettings.event_charge``
  x ``w`` once they happen at all (``is_success`` forbids each);
- ``obstacle``: ``-w/2`` x (``sqrt(min(1, steps touching the cup / 100))`` + ``sqrt(min(1, cup displacement /
  20 cm))``), each charged in the step in which it grows (touching it, pushing it further); the square
  roots make a brief touch or a small push cost much (1 step: 0.05 w, 2 cm: 0.16 w) while a learner that
  only shortens the contact still sees the cost fall;
- ``joint_limit``: ``-w`` x fraction of steps with a joint within the margin of its limit;
- ``invalid``: ``-w`` x (1 + severity in [0, 1]) for parameters rejected before simulation, or an episode
  in which a robot geom penetrated the robot's body or the table beyond the allowed depth (uniform trace);
- ``unstable``: ``-w`` if the simulation diverged (then the episode ends at that step).
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from ...smoothness import Smoothness
from .simulation import WipeTrace

__all__ = ["COVERAGE_TIMINGS", "TERMS", "RewardSettings", "RewardWeights", "Smoothness", "invalid_reward",
           "wipe_reward"]

#: where the cost trace books the coverage (:attr:`RewardSettings.coverage_timing`)
COVERAGE_TIMINGS = ("end", "wiped")
TERMS = ("coverage", "force", "excess_force", "contact_loss", "impact", "smoothness", "joint_accel",
         "arm_collision", "self_collision", "obstacle", "joint_limit", "invalid", "unstable")


@dataclass(frozen=True)
class RewardWeights:
    """Weight of each reward term (see the module docstring); all >= 0."""

    coverage: float = 1.0
    force: float = 0.2
    excess_force: float = 1.0
    contact_loss: float = 0.5
    impact: float = 0.3
    smoothness: float = 0.25
    joint_accel: float = 0.3
    arm_collision: float = 1.0
    self_collision: float = 1.0
    obstacle: float = 1.0
    joint_limit: float = 0.5
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
    """Thresholds of the reward.

    Attributes:
        target_force: the normal force F* to hold while wiping (N).
        force_sigma: width of the force-closeness score (N).
        max_force: forces above this are penalised (N) (the top of the wiping band).
        contact_threshold: a normal force below this counts as no contact (N).
        impact_force: touchdown peak force F_imp above which the impact is charged (N).
        max_joint_accel: commanded joint acceleration a_max above which the peak is charged (rad/s²).
        touch_steps: steps of touching the obstacle that cost the full obstacle-touch charge.
        obstacle_shift: obstacle displacement that costs the full obstacle-displacement charge (m).
        coverage_timing: where the cost trace books the coverage: ``"end"`` (at the last step) or ``"wiped"``
            (each step the dirt it removed); the sum is the same.
        event_charge: a fixed share of the weight that an arm collision, a self-collision, a joint at its limit
            or a joint acceleration above ``max_joint_accel`` costs as soon as it happens once (at its first
            step), on top of its graded cost (``ArmarWipe-v2``: 0.2, so that a brief graze, which ``is_success``
            forbids, costs more than the coverage it buys; v1: 0).
    """

    target_force: float = 18.0
    force_sigma: float = 6.0
    max_force: float = 60.0
    contact_threshold: float = 1.0
    impact_force: float = 40.0
    max_joint_accel: float = 10.0
    touch_steps: int = 100
    obstacle_shift: float = 0.2
    event_charge: float = 0.0
    coverage_timing: str = "end"


def _terms(parts: dict[str, np.ndarray], traces: dict | None) -> tuple[dict[str, float], np.ndarray]:
    """Cost traces per term ``[T]`` -> (reward terms = -sum of each trace, total cost trace ``[T]``); the
    per-term traces are copied into ``traces`` if given."""
    if traces is not None:
        traces.update(parts)
    terms = {name: -float(np.sum(parts[name])) + 0.0 for name in TERMS}
    trace = np.sum([parts[name] for name in TERMS], axis=0)
    return terms, trace


def _growth(values: np.ndarray) -> np.ndarray:
    """Per-step increments ``[T]`` of the running maximum of ``values [T]`` (they sum to its maximum)."""
    return np.diff(np.maximum.accumulate(values), prepend=0.0)


def wipe_reward(trace: WipeTrace, periodic: np.ndarray, smooth: Smoothness, settings: RewardSettings,
                weights: RewardWeights, traces: dict | None = None) -> tuple[dict[str, float], np.ndarray]:
    """Reward terms and the per-step cost trace ``[T]`` of a simulated wipe.

    Args:
        trace: the simulation record (``T`` control steps; only the first ``trace.steps`` count).
        periodic: mask ``[T]`` of the steps in the periodic (wiping) phase.
        smooth: smoothness of the commanded motion.
        traces: if given, filled with each term's cost trace ``{term: [T]}``.
    """
    count = len(trace.contact_force)
    live = np.arange(count) < trace.steps
    last = max(trace.steps, 1) - 1
    force = trace.contact_force
    per = periodic & live
    n_per = max(1, int(np.count_nonzero(periodic)))
    parts = {name: np.zeros(count) for name in TERMS}
    if settings.coverage_timing == "wiped":
        parts["coverage"] = -weights.coverage * np.where(live, trace.removed, 0.0)
    else:
        parts["coverage"][last] = -weights.coverage * float(np.sum(trace.removed))
    score = np.exp(-0.5 * ((force - settings.target_force) / settings.force_sigma) ** 2)
    parts["force"] = -weights.force * np.where(per, score, 0.0) / n_per
    excess = np.minimum(1.0, np.maximum(0.0, force - settings.max_force) / settings.max_force)
    parts["excess_force"] = weights.excess_force * np.where(live, excess, 0.0) / count
    parts["contact_loss"] = weights.contact_loss * (per & (force < settings.contact_threshold)) / n_per
    if trace.impact_step >= 0:
        over = max(0.0, trace.impact_force - settings.impact_force) / settings.impact_force
        parts["impact"][trace.impact_step] = weights.impact * min(1.0, over)
    total_jerk = float(np.sum(smooth.jerk_sq))
    if smooth.jerk_ratio > 1.0 and total_jerk > 0:
        parts["smoothness"] = weights.smoothness * np.log(smooth.jerk_ratio) * smooth.jerk_sq / total_jerk
    peak = int(np.argmax(smooth.joint_accel))
    over = max(0.0, float(smooth.joint_accel[peak]) - settings.max_joint_accel) / settings.max_joint_accel
    parts["joint_accel"][peak] = weights.joint_accel * (min(1.0, over) + (settings.event_charge if over > 0 else 0))
    charge = settings.event_charge
    parts["arm_collision"] = weights.arm_collision * _with_event((trace.arm_contact & live) / count, charge)
    parts["self_collision"] = weights.self_collision * _with_event((trace.self_contact & live) / count, charge)
    touching = np.sqrt(np.minimum(1.0, np.cumsum(trace.obstacle_contact & live) / settings.touch_steps))
    shifted = np.sqrt(np.minimum(1.0, trace.obstacle_shift / settings.obstacle_shift))
    parts["obstacle"] = 0.5 * weights.obstacle * (_growth(touching) + _growth(shifted))
    parts["joint_limit"] = weights.joint_limit * _with_event((trace.at_limit & live) / count, charge)
    if trace.unstable:
        # The rest of the episode is lost: it counts as if the sponge lost contact from here on.
        lost = periodic & ~live
        parts["contact_loss"] = parts["contact_loss"] + weights.contact_loss * lost / n_per
        parts["unstable"][last] = weights.unstable
    return _terms(parts, traces)


def _with_event(graded: np.ndarray, charge: float) -> np.ndarray:
    """A graded per-step cost ``[T]`` plus ``charge`` at its first nonzero step (unchanged if it is all 0)."""
    steps = np.flatnonzero(graded)
    if charge and steps.size:
        graded = graded.copy()
        graded[steps[0]] += charge
    return graded


def invalid_reward(severity: float, count: int, weights: RewardWeights, traces: dict | None = None
                   ) -> tuple[dict[str, float], np.ndarray]:
    """Terms and a uniform cost trace ``[count]`` for parameters rejected before simulation (or an episode
    voided by penetration)."""
    severity = float(np.clip(severity, 0.0, 1.0))
    parts = {name: np.zeros(count) for name in TERMS}
    parts["invalid"] = np.full(count, weights.invalid * (1.0 + severity) / count)
    return _terms(parts, traces)
