"""The envs' info keys are the ones rdmp_gym.envs.info defines, for simulated and for voided episodes."""

import gymnasium as gym
import numpy as np
import rdmp_gym.envs  # noqa: F401  (registers the ids)
from rdmp_gym.envs.info import EPISODE_KEYS, SCALAR_STATISTICS, STEP_KEYS, TRACE_STATISTICS

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
