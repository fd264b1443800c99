"""The DMP's residual step env: a = 0 is the wrapper's episode bit for bit, the residual moves the command by its
scale, the observation tells the DMP's desired state, bad input is refused, the env checkers pass."""

import os

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import gymnasium as gym
import numpy as np
import pytest
from rdmp_gym.envs.blackbox import RESIDUAL_ID, RhythmicResidualEnv, make_blackbox, make_residual

SHORT = {"duration": 1.0}          # Swimmer: 25 env steps of 0.04 s


@pytest.fixture(scope="module")
def residual():
    env = make_residual("Swimmer-v5", **SHORT)
    yield env
    env.close()


def _episode(env, action_of_step, seed=3):
    """(rewards [T], observations [T + 1, m]) of one episode with ``action_of_step(k)``."""
    observation, _ = env.reset(seed=seed)
    rewards, observations, done, k = [], [observation], False, 0
    while not done:
        observation, reward, terminated, truncated, _ = env.step(action_of_step(k))
        rewards.append(reward)
        observations.append(observation)
        done, k = terminated or truncated, k + 1
    return np.array(rewards), np.array(observations)


def test_the_zero_residual_is_the_wrappers_episode_bit_for_bit(residual):
    box = make_blackbox("Swimmer-v5", **SHORT)
    action = np.zeros(box.action_space.shape, np.float32)
    box.reset(seed=3)
    info = box.step(action)[4]
    rewards, observations = _episode(residual, lambda k: np.zeros(2, np.float32))
    np.testing.assert_array_equal(rewards, info["step_rewards"])
    assert len(rewards) == box.n_steps == 25
    q_des, qd_des = info["desired_positions"], info["desired_velocities"]
    d = box.n_joints
    np.testing.assert_allclose(observations[:-1, -2 * d:-d], q_des[1:], rtol=0, atol=1e-6)    # float32
    np.testing.assert_allclose(observations[:-1, -d:], qd_des[1:], rtol=0, atol=1e-6)
    box.close()


def test_a_residual_moves_the_gait_and_scale_zero_removes_it(residual):
    push = lambda k: np.array([1.0, -1.0], np.float32) * (-1) ** k      # noqa: E731
    zero_rewards, zero_observations = _episode(residual, lambda k: np.zeros(2, np.float32))
    rewards, observations = _episode(residual, push)
    assert not np.allclose(observations[1:, :8], zero_observations[1:, :8], atol=1e-3)
    assert not np.array_equal(rewards, zero_rewards)
    silent = RhythmicResidualEnv(residual.blackbox, scale=0.0)
    silent_rewards, _ = _episode(silent, push)
    np.testing.assert_array_equal(silent_rewards, zero_rewards)


def test_the_dmp_action_sets_the_pattern(residual):
    wider = RhythmicResidualEnv(residual.blackbox, dmp_action=np.full(residual.blackbox.action_space.shape, 0.5))
    zero = lambda k: np.zeros(2, np.float32)                             # noqa: E731
    assert not np.array_equal(_episode(wider, zero)[0], _episode(residual, zero)[0])


def test_bad_input_is_refused_naming_the_argument(residual):
    box = residual.blackbox
    with pytest.raises(ValueError, match="scale"):
        RhythmicResidualEnv(box, scale=-0.1)
    with pytest.raises(ValueError, match="dmp_action"):
        RhythmicResidualEnv(box, dmp_action=np.zeros(3))
    with pytest.raises(TypeError, match="blackbox"):
        RhythmicResidualEnv(gym.make("Swimmer-v5"))
    fresh = RhythmicResidualEnv(box)
    with pytest.raises(RuntimeError, match="reset"):
        fresh.step(np.zeros(2, np.float32))
    fresh.reset(seed=0)
    with pytest.raises(ValueError, match="action"):
        fresh.step(np.zeros(3, np.float32))
    with pytest.raises(ValueError, match="action"):
        fresh.step(np.array([np.nan, 0.0], np.float32))


def test_gym_make_builds_it_and_the_env_checkers_pass():
    from gymnasium.utils.env_checker import check_env
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    env = gym.make(RESIDUAL_ID, env_id="Swimmer-v5", scale=0.2, **SHORT)
    assert env.unwrapped.scale == 0.2 and env.observation_space.shape == (8 + 2 * 2,)
    with pytest.warns(UserWarning, match="infinity"):        # the DMP's desired state is unbounded, as the env's own
        check_env(env.unwrapped, skip_render_check=True)
    sb3_check_env(env.unwrapped, warn=False)
    env.close()


def test_a_controller_that_gives_no_finite_command_is_refused_before_the_env_steps():
    box = make_blackbox("Swimmer-v5", **SHORT)
    env = RhythmicResidualEnv(box)
    env.reset(seed=0)
    box.controller = lambda *state: np.array([np.nan, 0.0])
    with pytest.raises(ValueError, match="controller"):
        env.step(np.zeros(2, np.float32))
    env.close()
