"""The open-loop oscillator baseline (benchmarks/bench_open_loop_oscillator.py) and the wrapper's default patterns
that stand beside it (Swimmer: the published oscillator with a short start from rest; HalfCheetah: a tuned gait)."""

from __future__ import annotations

import bench_open_loop_oscillator as osc
import gymnasium as gym
import numpy as np
import pytest
from rdmp_gym.envs.blackbox import BlackBoxSettings, default_demonstration, make_blackbox


@pytest.fixture(scope="module")
def short_swimmer():
    env = gym.make("Swimmer-v5", max_episode_steps=50)
    yield env
    env.close()


def random_policy(env: gym.Env, setting: osc.EnvSetting, seed: int) -> tuple[osc.Oscillator, object]:
    space, joints = osc.env_space(env, setting)
    x = np.random.default_rng(seed).uniform(-1.0, 1.0, space.size)
    return osc.Oscillator(space.decode(x), setting.kp, setting.kd, env.action_space.low, env.action_space.high), joints


# ------------------------------------------------------------------ the oscillator
def test_the_space_decodes_the_unit_box_into_the_joints_ranges(short_swimmer):
    space, _ = osc.env_space(short_swimmer, osc.ENVS["Swimmer-v5"])
    assert space.size == 7                                      # 2 amplitudes, 2 phases, 2 offsets, 1 frequency
    low, high = space.decode(-np.ones(7)), space.decode(np.ones(7))
    np.testing.assert_allclose(low.amplitude, 0.0)
    np.testing.assert_allclose(high.amplitude, np.radians(100.0))   # half of Swimmer's hinge range of 200 degrees
    np.testing.assert_allclose(high.phase, 2.0 * np.pi)
    assert low.f_swing == low.f_stance == 0.2 and high.f_swing == 1.5
    split = osc.OscillatorSpace(np.ones(6), np.zeros(6), (0.5, 5.0), split=True)
    assert split.size == 20                                     # HalfCheetah's 6 x 3 + 2 frequencies
    with pytest.raises(ValueError, match=r"^x: expected shape \(20,\)"):
        split.decode(np.zeros(7))
    with pytest.raises(ValueError, match=r"^frequency: "):
        osc.OscillatorSpace(np.ones(2), np.zeros(2), (2.0, 1.0), split=False)


def test_the_torques_stay_in_the_box_and_an_episode_repeats_for_its_seed(short_swimmer):
    policy, joints = random_policy(short_swimmer, osc.ENVS["Swimmer-v5"], seed=3)
    far = policy(np.full(2, 5.0), np.full(2, -40.0), 0.04)     # far from the desired state: the PD saturates
    assert np.all(far >= -1.0) and np.all(far <= 1.0) and np.any(np.abs(far) == 1.0)
    first = osc.episode(short_swimmer, joints, policy, seed=11)
    again = osc.episode(short_swimmer, joints, policy, seed=11)
    assert first == again and first[1] == 50
    assert osc.episode(short_swimmer, joints, policy, seed=12)[0] != first[0]


def test_the_split_runs_the_swing_and_the_stance_at_their_own_rates():
    params = osc.OscillatorParams(np.ones(1), np.zeros(1), np.zeros(1), f_swing=1.0, f_stance=0.25)
    policy = osc.Oscillator(params, 1.0, 0.0, -np.ones(1), np.ones(1))
    steps, dt = 0, 0.001
    while policy.theta[0] < np.pi:                              # the swing half: sin(theta) > 0
        policy(np.zeros(1), np.zeros(1), dt)
        steps += 1
    assert steps * dt == pytest.approx(0.5, abs=2 * dt)         # half a period at 1 Hz
    while policy.theta[0] < 2.0 * np.pi:                        # the stance half
        policy(np.zeros(1), np.zeros(1), dt)
        steps += 1
    assert steps * dt == pytest.approx(0.5 + 2.0, abs=3 * dt)   # then half a period at 0.25 Hz


# ------------------------------------------------------------------ the CMA-ES loop
def test_cma_best_is_the_running_maximum_and_replays_from_its_seed(short_swimmer):
    setting = osc.ENVS["Swimmer-v5"]
    result = osc.cma_search(short_swimmer, setting, seed=5, budget=400, popsize=4, eval_seeds=[1], test_seeds=[2])
    returns, best_so_far = np.array(result["returns"]), np.array(result["best_so_far"])
    assert returns.size == 8 and result["env_steps"] == 400 and len(result["train_seeds"]) == 8
    assert [mark["env_steps"] for mark in result["curve"]] == [200, 400]
    assert np.all(np.diff(best_so_far) >= 0.0)
    np.testing.assert_array_equal(best_so_far, np.maximum.accumulate(returns))
    assert result["best"] == returns.max() == result["curve"][-1]["best_so_far"]
    best = osc.OscillatorParams.from_dict(result["best_params"])
    _, joints = osc.env_space(short_swimmer, setting)
    policy = osc.Oscillator(best, setting.kp, setting.kd, short_swimmer.action_space.low,
                            short_swimmer.action_space.high)
    replay = osc.episode(short_swimmer, joints, policy, result["train_seeds"][int(returns.argmax())])[0]
    assert replay == pytest.approx(result["best"], rel=1e-9)
    assert np.isfinite(result["final"]) and result["train_cpu_s"] > 0.0
    with pytest.raises(ValueError, match=r"^budget: "):
        osc.cma_search(short_swimmer, setting, seed=5, budget=0)


# ------------------------------------------------------------------ the Swimmer default beside it
def test_swimmer_default_swims_as_far_as_the_published_oscillator():
    seed = 1     # measured: the default 351.9, the published oscillator 352.0; a start of one period 343.7
    published = osc.published_swimmer([seed])[0]
    default = osc.wrapper_default("Swimmer-v5", [seed])[0]
    assert default >= 349.0 and default >= published - 1.0


def test_halfcheetah_default_runs_upright():
    env = make_blackbox("HalfCheetah-v5")
    env.reset(seed=0)
    _, episode_return, _, _, info = env.step(np.zeros(env.action_space.shape, np.float32))
    upright = abs(env.env.unwrapped.data.qpos[2]) < 1.0                 # the root's pitch: not on its back
    env.close()
    assert episode_return >= 950.0 and upright and info["env_steps"] == 1000     # measured: 1055


def test_the_start_from_rest_is_a_setting_in_periods():
    demo, segmentation = default_demonstration(np.zeros(2), 2.0, 0.3, start=0.25)
    assert segmentation.transient_length == pytest.approx(0.5) and demo.t[-1] == pytest.approx(4.25 * 2.0)
    assert np.abs(demo.Y[demo.t <= 0.0]).max() == 0.0 and np.abs(demo.Y[demo.t >= 0.5]).max() > 0.29
    assert BlackBoxSettings(start_periods=0.5).start_periods == 0.5
    with pytest.raises(ValueError, match=r"^start_periods: .* >= 0.05"):
        BlackBoxSettings(start_periods=0.01)
    with pytest.raises(ValueError, match=r"^start_periods: "):
        make_blackbox("Swimmer-v5", duration=1.0, start_periods=float("nan"))
