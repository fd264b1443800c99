"""The drumming task: the metronome, strikes from the 500 Hz force, the beats' score, the context, and episodes on both
robots (the imitation on the beat at a steady tempo, late after a change it cannot foresee, the stop at rest, cheap
strategies failing, the step twin's zero action equal to the episodic action 0)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import rdmp_gym.envs  # noqa: F401  (registers the ids)
from rdmp_gym.envs.tasks.drumming import DrumContextSpec, Metronome, Strikes, score_beats

STEADY = {"tempo": 90.0, "new_tempo": 90.0, "change_time": np.inf}
CHANGE = {"tempo": 85.0, "new_tempo": 100.0, "change_time": 4.3}


@pytest.fixture(scope="module", params=["Armar", "Panda"])
def env(request):
    env = gym.make(f"rdmp_gym/{request.param}Drum-v1")
    yield env
    env.close()


def _zero(env) -> np.ndarray:
    return np.zeros(env.action_space.shape, np.float32)


def _episode(env, options, action=None, seed=0):
    env.reset(seed=seed, options=options)
    _, reward, terminated, truncated, info = env.step(_zero(env) if action is None else action)
    assert terminated and not truncated
    return reward, info


# ------------------------------------------------------------------ metronome, strikes, beats
@pytest.mark.parametrize(("tempo", "new", "near"), [(60.0, 72.0, 4.0), (120.0, 96.0, 3.6), (100.0, 100.0, np.inf)])
def test_the_metronome_changes_tempo_once_at_a_beat(tempo, new, near):
    metronome = Metronome.changing_at_beat(tempo, new, near, start_phase=2.0, strike_phase=0.7)
    beats = metronome.beats(10.0)
    gaps = np.diff(beats)
    before = beats[1:] <= metronome.change_time + 1e-9
    assert np.allclose(gaps[before], 60.0 / tempo) and np.allclose(gaps[~before], 60.0 / new)
    assert np.allclose(np.mod(metronome.phase(beats) - 0.7 + np.pi, 2 * np.pi) - np.pi, 0.0, atol=1e-9)
    if np.isfinite(near):
        assert np.min(np.abs(beats - metronome.change_time)) < 1e-9 and abs(metronome.change_time - near) <= 30 / tempo
    assert np.allclose(metronome.signal(beats, shift=0.7), 1.0)


def test_strikes_are_runs_of_force_merged_across_chatter_and_integrated():
    dt = 0.002
    force = np.zeros(1000)
    force[100:110] = 20.0                 # a strike: 20 N for 20 ms
    force[300:305] = 10.0                 # a bounce with a 6 ms gap: one strike
    force[308:312] = 10.0
    force[600:700] = 0.3                  # below the threshold: no strike
    strikes = Strikes.from_force(force, dt)
    assert np.allclose(strikes.onsets, [101 * dt, 301 * dt])
    assert np.allclose(strikes.impulses, [20 * 10 * dt, 10 * 9 * dt])
    assert np.allclose(strikes.peaks, [20.0, 10.0])


def test_beats_are_struck_once_on_time_and_in_band():
    beats = np.array([1.0, 2.0, 3.0, 4.0])
    onsets = np.array([1.01, 2.2, 3.0, 3.3, 5.6])        # on time, late, a double bounce, outside every window
    strikes = Strikes(onsets, np.array([0.5, 0.5, 0.5, 0.5, 0.5]), np.ones(5), np.zeros(5, int))
    score = score_beats(strikes, beats, tolerance=0.05, band=(0.1, 1.0))
    assert score.count.tolist() == [1, 1, 2, 0]
    assert score.struck.tolist() == [True, False, False, False]
    assert score.extra == 1
    soft = score_beats(Strikes(np.array([1.0]), np.array([0.05]), np.ones(1), np.zeros(1, int)), beats, 0.05,
                       (0.1, 1.0))
    assert not soft.struck[0]


def test_the_context_is_drawn_inside_its_bounds_and_options_are_checked_by_name():
    spec = DrumContextSpec()
    rng = np.random.default_rng(0)
    for _ in range(50):
        context = spec.sample(rng)
        assert np.all(context.vector() >= spec.low) and np.all(context.vector() <= spec.high)
        assert spec.tempo[0] <= context.new_tempo <= spec.tempo[1]
    assert spec.sample(rng, {"tempo": 70.0}).tempo == 70.0
    with pytest.raises(ValueError, match="tempo"):
        spec.sample(rng, {"tempo": 300.0})
    with pytest.raises(ValueError, match="drum_height"):
        spec.sample(rng, {"drum_height": [0.1, 0.2]})
    with pytest.raises(ValueError, match="unknown"):
        spec.sample(rng, {"cup": 1})


# ------------------------------------------------------------------ episodes
def test_the_imitation_drums_on_the_beat_at_a_steady_tempo_and_stops_at_rest(env):
    reward, info = _episode(env, STEADY)
    assert info["is_success"], info["failure_causes"]
    counted = info["counted_beats"]
    assert counted.sum() >= 5 and info["struck_fraction"] == 1.0
    assert np.all(np.abs(info["timing_error"][counted]) < 0.05)
    assert np.all(info["strike_times"] < info["beat_times"][-1] + 0.2)          # nothing after the last beat
    assert info["end_speed"] < 0.02 and info["jerk_ratio"] == pytest.approx(1.0)
    face = env.unwrapped
    assert info["force_trace"].shape == (face.n_steps * face.frame_skip,)     # the membrane's force at 500 Hz
    assert np.isclose(reward, -info["cost_trace"].sum())


def test_after_a_tempo_change_the_default_coupling_lags_and_a_stronger_one_follows(env):
    _, default = _episode(env, CHANGE)
    assert not default["is_success"] and "timing" in default["failure_causes"]
    late = default["timing_error"][default["beat_times"] > CHANGE["change_time"] + 0.1]
    assert np.nanmax(np.abs(late)) > 0.05
    action = _zero(env)
    size = env.unwrapped.action_map.size
    action[size:size + 3] = [0.67, 0.5, -0.5]                   # coupling K = 8, k_phi = 5.7, strike 0.5 rad earlier
    _, coupled = _episode(env, CHANGE, action)
    assert coupled["struck_fraction"] > default["struck_fraction"]


def test_the_same_seed_gives_the_same_numbers():
    first, second = gym.make("rdmp_gym/ArmarDrum-v1"), gym.make("rdmp_gym/ArmarDrum-v1")
    action = np.random.default_rng(3).uniform(-0.3, 0.3, first.action_space.shape).astype(np.float32)
    one, two = _episode(first, None, action, seed=11), _episode(second, None, action, seed=11)
    assert one[0] == two[0] and np.array_equal(one[1]["force_trace"], two[1]["force_trace"])


def test_standing_still_and_pressing_on_the_membrane_fail(env):
    face = env.unwrapped
    face.reset(seed=2, options=STEADY)
    imitation = face.imitation_plan.path
    _, still = face.run_path(np.repeat(imitation[:1], len(imitation), axis=0))
    assert not still["is_success"] and still["struck_fraction"] == 0.0
    pressing = imitation.copy()
    pressing[200:] = [0.0, 0.0, -0.005]
    reward, pressed = face.run_path(pressing)
    assert not pressed["is_success"] and reward < -1.0


def test_bad_actions_and_paths_are_refused_by_name(env):
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action"):
        env.step(np.zeros(3, np.float32))
    with pytest.raises(ValueError, match="action"):
        env.step(np.full(env.action_space.shape, np.nan, np.float32))
    with pytest.raises(ValueError, match="path"):
        env.unwrapped.run_path(np.zeros((5, 3)))
    with pytest.raises(ValueError, match="render_mode"):
        type(env.unwrapped)("drum", "armar3", render_mode="human")


@pytest.mark.parametrize("robot", ["Armar", "Panda"])
def test_the_step_twins_zero_action_is_the_episodic_action_zero(robot):
    episodic, twin = gym.make(f"rdmp_gym/{robot}Drum-v1"), gym.make(f"rdmp_gym/{robot}DrumStep-v1")
    reward, info = _episode(episodic, CHANGE, seed=4)
    observation, _ = twin.reset(seed=4, options=CHANGE)
    assert twin.observation_space.contains(observation)
    total, done = 0.0, False
    while not done:
        _, step_reward, terminated, truncated, step_info = twin.step(np.zeros(3))
        total, done = total + step_reward, terminated or truncated
    assert np.isclose(total, reward) and step_info["is_success"] == info["is_success"]
    assert np.array_equal(step_info["force_trace"], info["force_trace"])
