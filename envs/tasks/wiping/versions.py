"""What changes between the versions of the wiping task (``ArmarWipe-v1``, ``-v2``, ``-v3``, ``PandaWipe-v3`` and their
step twins).

=====================  ===========================  =====================================================
                        v1                           v2
=====================  ===========================  =====================================================
pattern                 loops in place at the patch  travels across the patch: ``sweep_x``, ``sweep_y``
                        centre                       action dimensions (:mod:`rdmp_gym.envs.tasks.wiping.coverage`)
periods                 4 after the transient        7 after the transient (wear needs the time)
cup clearance           1 cm from the patch          the pad's half-diagonal + 1 cm (7.1 cm for the 7 x 10
                                                     cm pad): the pad can wipe the patch edge past the cup
smoothness              jerk / the imitation's       jerk per unit of squared speed / the imitation's: a
                                                     larger or travelling pattern that is as smooth costs
                                                     nothing
``is_success``          coverage, force, collisions, also executable: peak joint acceleration within
                        cup                          ARMAR-III's limit, no joint at its limit
collisions, limits      charged per step             also a fixed 0.2 x weight once they happen at all, so
                                                     a graze costs more than the coverage it buys
=====================  ===========================  =====================================================

v3 keeps v2's task and changes: the scene is composed from the arena, a robot (``ArmarWipe-v3``: ARMAR-III,
``PandaWipe-v3``: a Franka Panda) and the sponge tool; ``is_success`` also needs a smooth path (speed-normalised
jerk within :data:`MAX_JERK_RATIO` of the imitation's, so that no uniformly random action succeeds); the cup's
displacement counts from the robot's first touch (a cup that settles untouched costs nothing); an episode voided
for penetration reports coverage 0 like every other voided episode; the step twin runs the episodic env's
simulation core. The versions 1 and 2 are described by
:class:`~rdmp_gym.envs.tasks.wiping.legacy.task.LegacyWipingTask` (on ARMAR-III's hand-merged scene), which reads
their :data:`TASK_VERSIONS`; version 3 is :class:`~rdmp_gym.envs.tasks.wiping.task.WipingTask`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["CUP_MARGIN", "LEARNER_DEFAULTS", "MAX_JERK_RATIO", "TASK_VERSIONS", "TaskVersion", "pad_clearance"]

#: Cup-rim clearance (m) beyond the pad's half-diagonal in v2.
CUP_MARGIN = 0.01
#: v3's ``is_success`` needs the path's speed-normalised jerk within this factor of the imitation's: learned
#: policies run at 1.0-1.3x, a smooth 6 cm lift over a cup at 2x, uniformly random actions at 7-25x.
MAX_JERK_RATIO = 3.0


@dataclass(frozen=True)
class TaskVersion:
    """The settings that differ between the task versions (the current one adds its own to version 2's: see the
    module docstring and :class:`~rdmp_gym.envs.tasks.wiping.task.WipingTask`).

    Attributes:
        version: 1, 2 or 3.
        n_periods: default periods of the pattern after the transient.
        sweep: the anchor travels along the covering sweep (action dimensions ``sweep_x``, ``sweep_y``).
        pad_clearance: the cup keeps the pad's half-diagonal plus :data:`CUP_MARGIN` from the patch (else 1 cm).
        speed_normalised_jerk: smoothness compares jerk per unit of squared speed (else plain jerk).
        executable_success: ``is_success`` also needs the peak joint acceleration within the limit and no
            joint at its limit.
        event_charge: what a collision, a joint at its limit or a joint acceleration above the limit costs as soon
            as it happens (a share of its weight, :class:`rdmp_gym.envs.tasks.wiping.reward.RewardSettings`).
    """

    version: int
    n_periods: float
    sweep: bool
    pad_clearance: bool
    speed_normalised_jerk: bool
    executable_success: bool
    event_charge: float


def pad_clearance(sponge_half: np.ndarray) -> float:
    """Clearance (m) between the cup's rim and the patch that lets a sponge box of half sizes ``[3]`` (face: 1, 2)
    wipe the patch's edge past the cup: the pad's half-diagonal plus :data:`CUP_MARGIN`."""
    return float(np.hypot(sponge_half[1], sponge_half[2])) + CUP_MARGIN


TASK_VERSIONS = {
    1: TaskVersion(1, n_periods=4.0, sweep=False, pad_clearance=False, speed_normalised_jerk=False,
                   executable_success=False, event_charge=0.0),
    2: TaskVersion(2, n_periods=7.0, sweep=True, pad_clearance=True, speed_normalised_jerk=True,
                   executable_success=True, event_charge=0.2),
    3: TaskVersion(3, n_periods=7.0, sweep=True, pad_clearance=True, speed_normalised_jerk=True,
                   executable_success=True, event_charge=0.2),
}


def _contextual_search(gain_groups: list[str]) -> dict:
    """The contextual searches' settings on the wiping task: the context sets the pattern's amplitudes and the
    approach's lift (and on the travelling versions the sweep), from the patch size and the cup's presence; every
    other weight is one shared refinement; the approach is explored over its whole range (only a lift near its full
    6 cm clears the cup, so a small step never shows its worth). Measured on training and validation contexts only
    (see the docs' agents page)."""
    return {"gain_groups": gain_groups, "features": ["patch_size", "obstacle"], "sigma_factors": {"approach": 3.0}}


_CONTEXTUAL = ("creps", "cpibb", "cpi2", "random")
#: the one-theta learners' and SB3's smooth exploration on the travelling versions (v1's runs keep theirs)
_SMOOTH = {agent: {"length": 5.0} for agent in ("pi2", "cmaes", "sac")}
_TRAVELLING = {**{agent: _contextual_search(["amplitude", "approach", "sweep_x", "sweep_y"]) for agent in _CONTEXTUAL},
               **_SMOOTH,
               # PPO's step size with smooth actions (at v1's 3e-2 the policy mean ran far outside the action box,
               # so nearly every weight was executed at a face; see the docs)
               "ppo": {"length": 5.0, "learning_rate": 3e-3}}

#: What a learner may read from the wiping task, per version: ``{agent: options}`` (a run's own options override
#: them; the episodic envs only, not the step twins).
LEARNER_DEFAULTS: dict[int, dict[str, dict]] = {
    1: {agent: _contextual_search(["amplitude", "approach"]) for agent in _CONTEXTUAL},
    2: _TRAVELLING,
    3: _TRAVELLING,
}
