"""The keys of the wiping envs' ``info``, defined once.

The episodic env returns all of them from every ``step``; the step twin from the last step of an episode (and
``STEP_KEYS`` from every step).
"""

from __future__ import annotations

import numpy as np

__all__ = ["EPISODE_KEYS", "SCALAR_STATISTICS", "STEP_KEYS", "TRACE_STATISTICS", "void_statistics"]

#: Scalar statistics of a simulated episode, with their value for an episode that was not simulated (rejected
#: before the simulation: coverage 0, no force, the jerk and the joint acceleration undefined).
SCALAR_STATISTICS: dict[str, float | int] = {
    "coverage": 0.0, "force_mean": 0.0, "force_sd": 0.0, "force_error_mean": 0.0, "force_in_band_fraction": 0.0,
    "contact_fraction": 0.0, "max_force": 0.0, "max_wrist_force": 0.0, "impact_force": 0.0,
    "jerk_ratio": float("nan"), "peak_joint_accel": float("nan"), "arm_collision_fraction": 0.0,
    "self_collision_fraction": 0.0, "penetration": 0.0, "obstacle_touch_steps": 0, "obstacle_shift": 0.0,
    "joint_limit_fraction": 0.0, "steps": 0,
}
#: Per-control-step traces of an episode, ``[T]`` each (``fine_force_trace``, ``[T * frame_skip]``, on request).
TRACE_STATISTICS = ("force_trace", "dirt_removed_trace")
#: What every episode's info holds beside its statistics.
EPISODE_KEYS = ("params", "reward_terms", "cost_trace", "cost_terms", "valid", "invalid_reason", "unstable",
                "is_success", "failure_causes", "n_cells")
#: What every step of the step twin returns.
STEP_KEYS = ("reward_terms", "coverage", "unstable", "contact_force", "wrist_force")


def void_statistics(n_steps: int) -> dict[str, object]:
    """The statistics of an episode of ``n_steps`` control steps that was not simulated."""
    return {**SCALAR_STATISTICS, **{key: np.zeros(n_steps) for key in TRACE_STATISTICS}}
