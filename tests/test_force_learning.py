"""Force-profile learning (rdmp_gym.envs.tasks.wiping.force_learning): a periodic depth profile learned from the force
error."""

import gymnasium as gym
import numpy as np
import pytest
import rdmp_gym.envs  # noqa: F401  (registers the env)
from rdmp_gym.envs import ENV_ID
from rdmp_gym.envs.controller import ForceAdaptation, ForceAdaptationSettings
from rdmp_gym.envs.tasks.wiping.force_learning import (
    ForceProfileLearning,
    ForceProfileSettings,
    curved_table_scene,
    period_force_errors,
    wavy_contact,
)

DT, PERIOD = 0.01, 1.5


@pytest.mark.parametrize("gain", [0.02, 0.004])       # the env's default admittance gain and a slow one
def test_learning_removes_the_periodic_error_of_a_curved_surface(gain):
    settings = ForceAdaptationSettings(target_force=18.0, gain=gain)
    plain = period_force_errors(wavy_contact(ForceAdaptation(settings, DT), DT, PERIOD, 12), DT, 0.0, PERIOD, 18.0,
                                smoothing=0.0)
    learned = period_force_errors(wavy_contact(ForceProfileLearning(settings, DT, PERIOD), DT, PERIOD, 12), DT, 0.0,
                                  PERIOD, 18.0, smoothing=0.0)
    assert np.all(np.isfinite(learned))
    assert plain[-3:].mean() > 0.3 and np.ptp(plain[2:]) < 1e-3     # the admittance leaves the same error each period
    assert np.all(np.diff(learned[1:]) < 0.0)                        # falls period by period
    assert np.all(learned[2:] < plain[2:])
    assert learned[-1] < 0.25 * plain[-1]


def test_the_learner_tracks_the_admittance_offset_exactly():
    # the profile's update uses the admittance's offset, which the episode loop keeps in a local variable: the
    # learner recomputes it, and must get the same numbers as ForceAdaptation's law
    settings = ForceAdaptationSettings(target_force=18.0)
    learner, reference = ForceProfileLearning(settings, DT, PERIOD), ForceAdaptation(settings, DT)
    rng = np.random.default_rng(0)
    for force, height in zip(rng.uniform(0.0, 40.0, 400), rng.uniform(-0.01, 0.03, 400), strict=True):
        learner.update(force, height)
        reference.update(force, height)
        assert learner.feedback == learner.offset == reference.offset


def test_settings_are_checked():
    for bad in (dict(n_basis=1), dict(gain=0.0), dict(gain=1.5), dict(delay=-0.1), dict(overlap=1.0)):
        with pytest.raises(ValueError, match=next(iter(bad))):
            ForceProfileSettings(**bad)
    with pytest.raises(ValueError, match="period"):
        ForceProfileLearning(ForceAdaptationSettings(), DT, -1.0)
    with pytest.raises(ValueError, match="delay"):
        ForceProfileLearning(ForceAdaptationSettings(), DT, 0.04, profile=ForceProfileSettings(delay=0.05))
    with pytest.raises(ValueError, match="force_learning"):
        gym.make(ENV_ID, force_learning="yes")


def episode(force_learning, tilt, **kwargs):
    env = gym.make(ENV_ID, n_periods=8.0, force_learning=force_learning, **kwargs)    # the default admittance gain
    env.reset(seed=0, options={"table_height": 0.0, "table_tilt": tilt, "patch_centre": [0.0, 0.0],
                               "patch_size": [0.12, 0.12], "sponge_start": [-0.07, 0.10, 0.08], "obstacle": 0})
    inner = env.unwrapped
    inner.task.fine_force = True
    _, reward, _, _, info = env.step(np.zeros(env.action_space.shape, dtype=np.float32))
    errors = period_force_errors(info["fine_force_trace"], inner.dt / inner.frame_skip,
                                 inner.dmp.transients[0].length, inner.dmp.period,
                                 inner.task.reward_settings.target_force, smoothing=0.0)   # the contact force at 500 Hz
    return reward, info, errors


def test_tilted_table_force_error_falls_period_by_period_in_mujoco():
    _, plain_info, plain = episode(False, [-0.10, 0.12])
    _, info, learned = episode(True, [-0.10, 0.12])
    assert plain_info["valid"] and info["valid"] and not info["unstable"]
    assert np.ptp(plain) < 0.02 and plain.mean() > 0.5               # the admittance leaves the same error each period
    assert np.all(np.diff(learned) < 0.0)                            # falls period by period
    assert np.all(learned[1:] < plain[1:])
    assert learned[-1] < 0.4 * plain[-1]
    assert info["coverage"] >= plain_info["coverage"] - 0.02


def test_curved_table_force_error_falls_period_by_period_in_mujoco(tmp_path):
    scene = str(curved_table_scene(tmp_path))
    _, plain_info, plain = episode(False, [0.0, 0.0], xml_file=scene)
    _, info, learned = episode(True, [0.0, 0.0], xml_file=scene)
    assert plain_info["valid"] and info["valid"] and not info["unstable"]
    assert np.ptp(plain[1:]) < 0.02 and plain.mean() > 1.0          # the curvature: a larger error, every period
    assert np.all(np.diff(learned) < 0.0)
    assert np.all(learned[1:] < plain[1:])
    assert learned[-1] < 0.45 * plain[-1]
    with pytest.raises(ValueError, match="crown"):
        curved_table_scene(tmp_path, crown=0.0)
