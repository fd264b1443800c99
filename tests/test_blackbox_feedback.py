"""The black-box wrapper's reacting policy (setting ``feedback="linear"``) on short Swimmer-v5 episodes."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from rdmp_gym.envs.blackbox import BLACKBOX_SCALES, RhythmicBlackBoxWrapper, make_blackbox, split_settings
from rdmp_gym.envs.blackbox.controller import FEEDBACK_CLIP, LinearFeedback

ENV = "Swimmer-v5"
DURATION = 2.0      # 50 env steps of 0.04 s


@pytest.fixture(scope="module")
def pair() -> tuple[RhythmicBlackBoxWrapper, RhythmicBlackBoxWrapper]:
    """The open-loop wrapper and the one with feedback, otherwise alike."""
    plain, reacting = make_blackbox(ENV, duration=DURATION), make_blackbox(ENV, duration=DURATION, feedback="linear")
    yield plain, reacting
    plain.close()
    reacting.close()


def _episode(env: RhythmicBlackBoxWrapper, action: np.ndarray, seed: int) -> tuple[float, dict]:
    env.reset(seed=seed)
    _, episode_return, _, _, info = env.step(np.asarray(action, dtype=np.float32))
    return episode_return, info


def test_zero_action_is_the_open_loop_gait_bit_for_bit(pair):
    plain, reacting = pair
    for seed in (3, 11):
        r_plain, plain_info = _episode(plain, np.zeros(plain.action_space.shape), seed)
        r_react, react_info = _episode(reacting, np.zeros(reacting.action_space.shape), seed)
        assert r_react == r_plain
        assert np.array_equal(react_info["env_actions"], plain_info["env_actions"])
        assert np.array_equal(react_info["positions"], plain_info["positions"])
        assert not np.any(react_info["feedback_actions"])
        assert "feedback_actions" not in plain_info


def test_the_action_grows_by_one_gain_per_action_and_feature(pair):
    plain, reacting = pair
    n, m = reacting.env_action_space.shape[0], gym.spaces.flatten_space(reacting.env.observation_space).shape[0]
    assert reacting.action_space.shape[0] == plain.action_space.shape[0] + n * m
    slices = reacting.action_slices()
    assert list(slices)[-1] == "feedback" and slices["feedback"].stop == reacting.action_space.shape[0]
    assert {k: v for k, v in slices.items() if k != "feedback"} == plain.action_slices()
    weights = reacting.action_time_weights()
    assert weights.shape == (reacting.n_steps, reacting.action_space.shape[0])
    assert np.all(weights[:, slices["feedback"]] == 1.0)
    action = np.random.default_rng(0).uniform(-1, 1, reacting.action_space.shape).astype(np.float32)
    theta = reacting.action_to_params(action)
    np.testing.assert_allclose(reacting.params_to_action(theta), action, atol=1e-6)
    assert reacting.policy_dmp(theta).n_dims == plain.dmp.n_dims


def test_a_gain_moves_the_command_the_predicted_way(pair):
    plain, reacting = pair
    seed, i = 5, 1
    reacting.reset(seed=seed)
    z0 = reacting.feedback.features(reacting._reset_observation)
    j = int(np.argmax(np.abs(z0)))                      # the feature that deviates most at the reset
    n, m = reacting.param_map.feedback_shape
    half = (reacting.env_action_space.high - reacting.env_action_space.low)[i] / 2.0
    base = _episode(plain, np.zeros(plain.action_space.shape), seed)[1]["env_actions"][0]
    for gain in (0.5, -0.5):
        action = np.zeros(reacting.action_space.shape)
        action[reacting.action_slices()["feedback"].start + i * m + j] = gain
        commands = _episode(reacting, action, seed)[1]["env_actions"]
        predicted = gain * BLACKBOX_SCALES["feedback"] * half / np.sqrt(m) * z0[j]
        assert abs(base[i] + predicted) < reacting.env_action_space.high[i]       # the prediction is not clipped
        change = commands[0] - base
        np.testing.assert_allclose(change[i], predicted, rtol=1e-5)
        assert np.sign(change[i]) == np.sign(gain * z0[j]) != 0
        assert np.all(change[np.arange(n) != i] == 0.0)                         # the other actuators: untouched


@pytest.mark.parametrize("value", ["pid", "Linear", 1, True])
def test_a_bad_feedback_value_is_refused_naming_the_setting(value):
    with pytest.raises(ValueError, match="feedback"):
        make_blackbox(ENV, duration=DURATION, feedback=value)


def test_feedback_is_no_group_to_select_and_passes_as_an_env_option():
    with pytest.raises(ValueError, match="groups"):
        make_blackbox(ENV, duration=DURATION, groups=("periodic", "feedback"))
    wrapper, env_kwargs = split_settings(ENV, {"feedback": "linear", "duration": DURATION})
    assert wrapper == {"feedback": "linear", "duration": DURATION} and env_kwargs == {}


def test_large_gains_are_clipped_by_the_action_box_and_never_give_nan(pair):
    _, reacting = pair
    low, high = reacting.env_action_space.low, reacting.env_action_space.high
    rng = np.random.default_rng(1)
    for action in (np.ones(reacting.action_space.shape), -np.ones(reacting.action_space.shape),
                   rng.uniform(-1, 1, reacting.action_space.shape)):
        action[reacting.action_slices()["feedback"]] = np.sign(action[reacting.action_slices()["feedback"]])
        episode_return, info = _episode(reacting, action, 2)
        assert np.isfinite(episode_return) and np.all(np.isfinite(info["positions"]))
        assert np.all(info["env_actions"] >= low) and np.all(info["env_actions"] <= high)
        assert info["clipped_fraction"] > 0.0 and np.all(np.isfinite(info["feedback_actions"]))


def test_the_standardisation_is_fixed_by_the_env_not_by_its_history(pair):
    _, reacting = pair
    env = gym.make(ENV)
    env.reset(seed=123)
    for _ in range(30):
        env.step(env.action_space.sample())
    other = RhythmicBlackBoxWrapper(env, duration=DURATION, feedback="linear")
    assert np.array_equal(other.feedback.mean, reacting.feedback.mean)
    assert np.array_equal(other.feedback.std, reacting.feedback.std)
    assert np.all(reacting.feedback.std > 0.0)
    other.close()


def test_linear_feedback_clips_and_floors():
    reference = np.array([[0.0, 1.0, 5.0], [2.0, 1.0, 5.0], [4.0, 1.0, 5.0]])   # features 1 and 2 never move
    feedback = LinearFeedback(reference)
    assert feedback.std[0] == pytest.approx(np.std([0.0, 2.0, 4.0]))
    assert np.all(feedback.std[1:] > 0.0)
    z = feedback.features(np.array([1e9, np.nan, 5.0]))
    assert z[0] == FEEDBACK_CLIP and z[1] == 0.0 and z[2] == 0.0
    np.testing.assert_allclose(feedback(np.array([[1.0, 0.0, 0.0]]), np.array([4.0, 1.0, 5.0])),
                               [2.0 / np.std([0.0, 2.0, 4.0])])
    with pytest.raises(ValueError, match="feedback"):
        LinearFeedback(np.zeros((0, 3)))
