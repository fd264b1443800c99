"""``rdmp_gym/ArmarWipeStep-v1``: Gymnasium's checker, a = 0 is the imitation with the episodic reward,
the bounded coupling moves the path by at most ``max_shift``, and plain SB3 SAC trains on it."""

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from rdmp_gym.envs import ENV_ID, STEP_ID

KWARGS = {"n_periods": 1, "control_rate": 50.0}


def _episode(env, action, seed):
    obs, _ = env.reset(seed=seed)
    total, positions, done = 0.0, [], False
    while not done:
        obs, reward, terminated, truncated, info = env.step(action)
        total += reward
        positions.append(obs[3:6])
        done = terminated or truncated
    return total, np.array(positions), info, terminated


@pytest.fixture(scope="module")
def env():
    environment = gym.make(STEP_ID, **KWARGS)
    yield environment
    environment.close()


def test_passes_gymnasium_checker(env):
    check_env(env.unwrapped, skip_render_check=True)
    obs, _ = env.reset(seed=0)
    assert obs.shape == env.observation_space.shape and env.observation_space.contains(obs)


def test_zero_action_is_the_imitation_with_the_episodic_reward(env):
    episodic = gym.make(ENV_ID, **KWARGS)
    episodic.reset(seed=3)
    _, reward, *_, info = episodic.step(np.zeros(episodic.action_space.shape, np.float32))
    total, _, step_info, terminated = _episode(env, np.zeros(3, np.float32), seed=3)
    assert not terminated
    assert total == pytest.approx(reward, abs=0.05)
    assert step_info["coverage"] == pytest.approx(info["coverage"], abs=0.03)


def test_a_constant_action_shifts_the_pattern_by_at_most_max_shift(env):
    _, rest, *_ = _episode(env, np.zeros(3, np.float32), seed=5)
    _, moved, *_ = _episode(env, np.array([1.0, 0.0, 0.0], np.float32), seed=5)
    late = slice(len(rest) // 2, None)
    shift = moved[late, 0].mean() - rest[late, 0].mean()
    assert 0.5 * 0.02 < shift < 1.2 * 0.02           # max_shift = 2 cm
    assert np.abs(moved[late, 1].mean() - rest[late, 1].mean()) < 0.005


def test_sb3_sac_trains_on_it(env):
    from stable_baselines3 import SAC

    model = SAC("MlpPolicy", env, learning_starts=40, batch_size=32, train_freq=8, gradient_steps=2, seed=0,
                device="cpu", verbose=0)
    model.learn(80)
    action, _ = model.predict(env.reset(seed=1)[0], deterministic=True)
    assert action.shape == (3,) and np.all(np.abs(action) <= 1.0)
