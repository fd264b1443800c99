"""The drum timing study's pieces (``benchmarks/bench_drum_timing.py``): the hand-made reactions' rules, the beats
counted from the tempo change, and one reaction's episode on the real env."""

import gymnasium as gym
import numpy as np
import pytest
from bench_drum_timing import REACTIONS, RetunedDrum, _action, _beats_since_change, _react, reaction, retuned
from rdmp_gym.envs.cycle_env import RhythmicCycleEnv


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


def test_the_retuned_follower_changes_only_the_cycles_that_retune():
    """RetunedDrum's tempo value at 0 in every cycle is the drumming cycle face's own episode; a retune at a cycle
    sets the follower's frequency from that cycle's start."""
    env = RhythmicCycleEnv(task=RetunedDrum(), robot="panda", version=1)
    plain = gym.make("rdmp_gym/PandaDrumCycle-v1").unwrapped
    returns = []
    for face in (env, plain):
        face.reset(seed=3)
        for _ in range(face.n_cycles):
            _, reward, terminated, _, _ = face.step(np.zeros(face.action_space.shape))
            if terminated:
                break
        returns.append(reward)
    assert returns[0] == returns[1] and env.action_space.shape[0] == plain.action_space.shape[0] + 1
    env.reset(seed=3)
    action = np.zeros(env.action_space.shape)
    for cycle in range(env.n_cycles):
        action[-1] = 0.0 if cycle < 4 else 0.4
        if env.step(action)[2]:
            break
    schedule = env._plan.extras["schedule"]
    step = int(env.start_steps[4])
    assert schedule.since == step and schedule.states[step, 5] == pytest.approx(
        env.face.task.metronome(env.face.context).omega * 2.0 ** 0.2)
    result = retuned("panda", np.array([1.0, 0.0, -0.5]), 0.0, 1)
    assert result["delay_beats"] == 0.0 and 0.0 <= result["success"]["estimate"] <= 1.0
    env.close()
    plain.close()
