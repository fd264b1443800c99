"""The envs' info keys are the ones rdmp_gym.envs.tasks.wiping.info defines, for simulated and for voided episodes."""

import gymnasium as gym
import numpy as np
import pytest
import rdmp_gym.envs  # noqa: F401  (registers the ids)
from rdmp_gym.envs.tasks.wiping.info import EPISODE_KEYS, SCALAR_STATISTICS, STEP_KEYS, TRACE_STATISTICS

EPISODE = {*SCALAR_STATISTICS, *TRACE_STATISTICS, *EPISODE_KEYS}


def test_a_simulated_and_a_rejected_episode_report_the_same_keys():
    env = gym.make("rdmp_gym/ArmarWipe-v3", n_periods=1.0)
    env.reset(seed=1)
    info = env.step(np.zeros(env.action_space.shape, np.float32))[-1]
    assert set(info) == EPISODE
    env.reset(seed=1)
    rejected = env.unwrapped.run_path(np.full((env.unwrapped.n_steps, 3), 5.0))[1]    # far outside the workspace
    assert rejected["invalid_reason"] == "workspace" and rejected["coverage"] == 0.0
    assert set(rejected) == EPISODE - {"params"} | {"params"}


def test_the_step_twin_reports_the_step_keys_and_at_the_end_the_episode_keys():
    env = gym.make("rdmp_gym/ArmarWipeStep-v3", n_periods=1.0)
    env.reset(seed=1)
    done, info = False, {}
    while not done:
        _, _, terminated, truncated, info = env.step(np.zeros(3))
        done = terminated or truncated
        assert set(STEP_KEYS) <= set(info)
    assert EPISODE - {"params", "n_cells"} <= set(info)


@pytest.mark.parametrize("env_id", ["rdmp_gym/ArmarWipe-v3", "rdmp_gym/PandaWipe-v3"])
def test_coverage_booked_when_wiped_keeps_the_return_and_spreads_the_trace(env_id):
    """``coverage_timing="wiped"``: the same return and terms, the coverage term spread over the wiping steps
    instead of booked at the last one; a bad value names the setting."""
    if env_id.startswith("rdmp_gym/Panda"):
        pytest.importorskip("gymnasium_robotics")
    results = {}
    for timing in ("end", "wiped"):
        env = gym.make(env_id, coverage_timing=timing)
        env.reset(seed=11)
        _, reward, _, _, info = env.step(np.zeros(env.action_space.shape))
        results[timing] = (reward, info)
        env.close()
    (end_reward, end), (wiped_reward, wiped) = results["end"], results["wiped"]
    assert wiped_reward == pytest.approx(end_reward, abs=1e-12)
    assert wiped["reward_terms"] == pytest.approx(end["reward_terms"], abs=1e-12)
    np.testing.assert_allclose(wiped["cost_trace"].sum(), -wiped_reward, atol=1e-12)
    booked_end, booked_wiped = end["cost_terms"]["coverage"], wiped["cost_terms"]["coverage"]
    assert np.count_nonzero(booked_end) == 1 and booked_end[-1] < 0
    assert np.count_nonzero(booked_wiped) > 100 and np.all(booked_wiped <= 0)
    assert booked_wiped[-1] > booked_end[-1]
    with pytest.raises(ValueError, match="coverage_timing"):
        gym.make(env_id, coverage_timing="later")
