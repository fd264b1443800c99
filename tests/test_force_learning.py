"""Force-profile learning (rdmp_gym.envs.force_learning): a periodic depth profile learned from the force error."""

import gymnasium as gym
import numpy as np
import pytest
from rdmp_gym.envs import ENV_ID
from rdmp_gym.envs.controller import ForceAdaptation, ForceAdaptationSettings
from rdmp_gym.envs.force_learning import ForceProfileLearning, ForceProfileSettings, period_force_errors

import rdmp_gym  # noqa: F401  (registers the env)

DT, PERIOD = 0.01, 1.5
# The profile is learned on top of a slow admittance (gain 0.004 m/(N s)): with the env's default gain 0.02 the
# admittance alone holds the force within the contact chatter (about 0.65 N on ArmarWipe-v1's compliant pad) and
# there is nothing periodic left to learn (README, issue 13).
SLOW = 0.004


def contact_plant(controller, periods=12, stiffness=1800.0, lag=0.03):
    """A surface whose height varies periodically with the phase, pressed through a first-order servo lag."""
    steps = round(periods * PERIOD / DT)
    t = np.arange(steps) * DT
    surface = 0.003 * np.sin(2.0 * np.pi * t / PERIOD) + 0.001 * np.cos(4.0 * np.pi * t / PERIOD + 0.5)
    position, force, trace = 0.0, 0.0, np.empty(steps)
    for k in range(steps):
        command = controller.update(force, 0.0)
        position += DT / lag * (command - position)
        force = max(stiffness * (position - surface[k]), 0.0)
        trace[k] = force
    return trace


def test_learning_removes_the_periodic_error_that_admittance_leaves():
    settings = ForceAdaptationSettings(target_force=18.0, gain=SLOW)
    plain = period_force_errors(contact_plant(ForceAdaptation(settings, DT)), DT, 0.0, PERIOD, 18.0, smoothing=0.0)
    learned = period_force_errors(contact_plant(ForceProfileLearning(settings, DT, PERIOD)), DT, 0.0, PERIOD, 18.0,
                                  smoothing=0.0)
    assert plain[-3:].mean() > 1.0                        # the admittance lags the surface: a periodic error stays
    assert learned[-1] < 0.5 * plain[-1]
    assert np.all(np.diff(learned) < 0.0)                  # falls period by period
    assert np.all(np.isfinite(learned))


def test_settings_are_checked():
    for bad in (dict(n_basis=1), dict(gain=0.0), dict(gain=1.5), dict(delay=-0.1), dict(overlap=1.0)):
        with pytest.raises(ValueError, match=next(iter(bad))):
            ForceProfileSettings(**bad)
    with pytest.raises(ValueError, match="period"):
        ForceProfileLearning(ForceAdaptationSettings(), DT, -1.0)
    with pytest.raises(ValueError, match="force_learning"):
        gym.make(ENV_ID, force_learning="yes")


def episode(force_learning, tilt):
    env = gym.make(ENV_ID, n_periods=10.0, force_learning=force_learning, admittance_gain=SLOW)
    env.reset(seed=0, options={"table_height": 0.0, "table_tilt": tilt, "patch_centre": [0.0, 0.0],
                               "patch_size": [0.12, 0.12], "sponge_start": [-0.07, 0.10, 0.08], "obstacle": 0})
    _, reward, _, _, info = env.step(np.zeros(env.action_space.shape, dtype=np.float32))
    inner = env.unwrapped
    errors = period_force_errors(info["force_trace"], inner.dt, inner.dmp.transients[0].length, inner.dmp.period,
                                 inner.reward_settings.target_force)
    return reward, info, errors


def test_tilted_table_force_error_falls_period_by_period_in_mujoco():
    _, plain_info, plain = episode(False, [-0.10, 0.12])
    _, info, learned = episode(True, [-0.10, 0.12])
    assert plain_info["valid"] and info["valid"] and not info["unstable"]
    assert plain[-3:].mean() > 1.5                         # the slow admittance leaves a periodic error
    assert learned[-3:].mean() < 0.5 * plain[-3:].mean()
    assert learned[-3:].mean() < 0.6 * learned[:2].mean()
    assert info["coverage"] >= plain_info["coverage"] - 0.02

