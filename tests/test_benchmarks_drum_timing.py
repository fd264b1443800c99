"""The drum timing study's pieces (``benchmarks/bench_drum_timing.py``): the hand-made reactions' rules, the beats
counted from the tempo change, and one episode of each reaction and retune on the real env."""

import gymnasium as gym
import numpy as np
import pytest
from bench_drum_timing import (
    HEARD_GAIN,
    REACTIONS,
    _action,
    _beats_since_change,
    _react,
    ear,
    heard,
    reaction,
    retuned,
)


def test_the_reaction_rules_correct_from_the_setting_or_from_the_last_value():
    assert _react("proportional", 3.0, -0.5, 0.2, 0.04) == pytest.approx(-0.62)      # from the setting
    assert _react("accumulated", 2.0, -0.5, 0.2, 0.04) == pytest.approx(0.12)        # from the last value
    assert _react("boost", 0.5, 0.5, 0.5, 0.04) == 1.0 and _react("boost", 0.5, 0.5, 1.0, 0.01) == 0.5


def test_beats_are_counted_from_the_first_at_the_new_tempo():
    info = {"beat_times": np.array([1.0, 1.6, 2.2, 2.7, 3.2]), "change_time": 2.0}
    np.testing.assert_array_equal(_beats_since_change(info), [-2, -1, 0, 1, 2])


def test_the_rhythm_values_alone_move_and_a_reaction_runs_on_the_cycle_face():
    env = gym.make("rdmp_gym/PandaDrum-v1")
    action = _action(env, np.array([0.5, -0.25, 0.3]))
    assert np.count_nonzero(action) == 3 and np.allclose(action[-3:], [0.5, -0.25, 0.3])
    result = reaction("rdmp_gym/PandaDrum-v1", np.array([0.5, 0.5, -0.5]), "proportional", 1)
    assert result["rule"] == REACTIONS["proportional"][1] and 0.0 <= result["success"]["estimate"] <= 1.0
    assert np.isfinite(result["timing_error"]) and result["jerk_ratio"] > 0


def test_the_oracle_retune_the_retune_by_ear_and_the_followers_ear_run_on_version_2():
    for result in (retuned("panda", np.array([1.0, 0.0, -0.5]), 0.0, 1),
                   heard("panda", np.array([1.0, 0.0, -0.5]), HEARD_GAIN, 1),
                   ear("panda", np.zeros(3), 1.0, 1)):
        assert 0.0 <= result["success"]["estimate"] <= 1.0 and np.isfinite(result["timing_error"])
        assert result["jerk_ratio"] > 0
