"""``rdmp_gym/ArmarWipe-v2``: the travelling pattern (sweep action), solvable contexts (cup clearance from the
pad), a smoothness cost that does not charge a pattern for its size, executable success, the step twin."""

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from rdmp_gym.envs import ENV_ID, ENV_ID_V2, STEP_ID_V2
from rdmp_gym.envs.smoothness import Smoothness
from rdmp_gym.envs.tasks.wiping.coverage import COVERING_FIGURE, covering_sweep, sweep_directions
from rdmp_gym.envs.tasks.wiping.env import episode_success, failure_causes

from rdmp_gym import Sweep, save_dmp

FAST = {"n_periods": 2, "control_rate": 50.0}       # a short, coarse episode for the API checks


@pytest.fixture(scope="module")
def env():
    environment = gym.make(ENV_ID_V2, **FAST)
    yield environment
    environment.close()


def _slices(env):
    return env.unwrapped.action_map.action_slices()


def test_v2_adds_two_sweep_dimensions_and_keeps_v1(env):
    v1 = gym.make(ENV_ID, **FAST)
    slices = _slices(env)
    assert env.action_space.shape[0] == v1.action_space.shape[0] + 2
    assert list(slices)[-3:] == ["approach", "sweep_x", "sweep_y"]
    assert "sweep" in env.unwrapped.task.groups and "sweep" not in v1.unwrapped.task.groups
    assert env.unwrapped.task.task_version.version == 2 and v1.unwrapped.task.task_version.version == 1
    assert gym.make(ENV_ID_V2).unwrapped.n_steps > gym.make(ENV_ID).unwrapped.n_steps    # 7 periods against 4


def test_action_zero_is_the_imitation_with_the_anchor_at_rest(env):
    env.reset(seed=4)
    base = env.unwrapped
    theta = base.action_to_params(np.zeros(env.action_space.shape))
    points = theta[base.param_slices()["sweep"]]
    assert np.all(points == 0.0)
    np.testing.assert_allclose(base.rollout_path(theta), base.task.imitation_path(base.context), atol=1e-9)
    *_, info = env.step(np.zeros(env.action_space.shape, np.float32))
    assert info["jerk_ratio"] == pytest.approx(1.0, abs=1e-9)
    assert info["reward_terms"]["smoothness"] == pytest.approx(0.0, abs=1e-9)


def test_the_sweep_carries_the_pattern_across_the_patch(env):
    env.reset(seed=4)
    base = env.unwrapped
    action = np.zeros(env.action_space.shape)
    action[_slices(env)["sweep_x"]] = 1.0
    action[_slices(env)["sweep_y"]] = -0.5
    moved = base.rollout_path(base.action_to_params(action))
    shift = moved - base.task.imitation_path(base.context)
    points = np.c_[COVERING_FIGURE * [0.06, -0.03], np.zeros(len(COVERING_FIGURE))]
    expected = base.dmp.sweep.offsets(base.times, points[None])[0]
    np.testing.assert_allclose(shift, expected, atol=2e-4)            # carried rigidly (to 0.2 mm at 50 Hz)
    assert np.abs(shift[~base.task.periodic]).max() < 1e-3             # the approach is the imitation's
    assert shift[:, 0].max() == pytest.approx(0.06, abs=1e-3)          # the figure's box, no overshoot
    assert np.abs(shift[:, 1]).max() == pytest.approx(0.03, abs=1e-3)
    assert np.abs(shift[-5:]).max() < 2e-4                             # back at rest at the centre


def test_sweep_action_and_parameters_round_trip(env):
    rng = np.random.default_rng(0)
    action = rng.uniform(-1, 1, env.action_space.shape)
    action[_slices(env)["approach"]] = 0.0        # expressed by the transient weights themselves on the way back
    theta = env.unwrapped.action_to_params(action)
    np.testing.assert_allclose(env.unwrapped.params_to_action(theta), action, atol=1e-5)
    off_figure = theta.copy()
    off_figure[env.unwrapped.param_slices()["sweep"].start] += 0.01
    with pytest.raises(ValueError, match="driven groups"):
        env.unwrapped.params_to_action(off_figure)


def test_time_weights_of_the_sweep_start_after_the_transient(env):
    weights = env.unwrapped.action_time_weights()
    assert weights.shape == (env.unwrapped.n_steps, env.action_space.shape[0])
    sweep = weights[:, _slices(env)["sweep_x"]].ravel()
    before = env.unwrapped.times < env.unwrapped.dmp.transients[0].length
    assert sweep[before].max() < 1e-9 and sweep.max() == pytest.approx(1.0)


def test_a_large_patch_needs_the_sweep_and_the_sweep_solves_it():
    """The largest drawn patch (0.22 m a side): the loop in place leaves it dirty; travelling with a larger
    loop wipes it, with a higher return (the reward's best is a success) and a smoothness cost near 0."""
    env = gym.make(ENV_ID_V2)
    options = {"patch_size": [0.22, 0.22], "patch_centre": [0.0, 0.0], "obstacle": 0}
    env.reset(seed=1, options=options)
    *_, imitation_reward, _, _, imitation = env.step(np.zeros(env.action_space.shape, np.float32))
    action = np.zeros(env.action_space.shape, np.float32)
    slices = _slices(env)
    action[slices["amplitude"].start:slices["amplitude"].start + 2] = 1.0
    action[slices["sweep_x"]], action[slices["sweep_y"]] = 0.7, 1.0
    env.reset(seed=1, options=options)
    _, reward, _, _, info = env.step(action)
    assert not imitation["is_success"] and imitation["coverage"] < 0.8
    assert info["is_success"] and info["coverage"] >= 0.95
    assert reward > imitation_reward + 0.2
    assert info["jerk_ratio"] < 1.15 and info["reward_terms"]["smoothness"] > -0.04


def test_rough_weights_still_pay_for_their_jerk(env):
    env.reset(seed=2, options={"obstacle": 0})
    action = np.zeros(env.action_space.shape, np.float32)
    periodic = _slices(env)["periodic"]
    action[periodic] = np.random.default_rng(0).uniform(-1.0, 1.0, periodic.stop - periodic.start)
    *_, info = env.step(action)
    assert info["jerk_ratio"] > 5.0 and info["reward_terms"]["smoothness"] < -0.4


@settings(max_examples=25, deadline=None)
@given(st.floats(0.05, 20.0), st.floats(-1.0, 1.0))
def test_speed_normalised_jerk_does_not_depend_on_size_or_place(factor, offset):
    t = np.arange(0.0, 3.0, 0.01)
    path = np.c_[np.cos(2 * np.pi * t) + 0.3 * np.cos(6 * np.pi * t), np.sin(2 * np.pi * t), 0.1 * t]
    reference = Smoothness.speed_normalised(path, 0.01)
    assert Smoothness.speed_normalised(factor * path + offset, 0.01) == pytest.approx(reference, rel=1e-9)


def test_the_cup_keeps_the_pads_clearance_from_the_patch():
    env = gym.make(ENV_ID_V2, **FAST).unwrapped
    half = env.task.parts.sponge_half
    clearance = float(np.hypot(half[1], half[2])) + 0.01
    assert env.task.context_spec.patch_clearance == pytest.approx(clearance)
    radius, cups = env.task.parts.obstacle_radius, 0
    for seed in range(200):
        context = env.task.context_spec.sample(np.random.default_rng(seed))
        if context.obstacle:
            cups += 1
            gap = np.maximum(np.abs(context.obstacle_position - context.patch_centre) - context.patch_size / 2, 0)
            assert np.hypot(*gap) - radius >= clearance - 1e-9
    assert cups > 20
    close = {"patch_centre": [0.0, 0.0], "patch_size": [0.1, 0.1], "obstacle": 1, "obstacle_position": [0.1, 0.0]}
    with pytest.raises(ValueError, match="obstacle_position"):
        env.reset(seed=0, options=close)                       # rim 1.5 cm from the patch: allowed in v1 only
    gym.make(ENV_ID, **FAST).reset(seed=0, options=close)


def test_success_needs_an_executable_motion():
    stats = {"coverage": 0.99, "force_in_band_fraction": 1.0, "arm_collision_fraction": 0.0,
             "self_collision_fraction": 0.0, "obstacle_touch_steps": 0, "obstacle_shift": 0.0,
             "peak_joint_accel": 4.0, "joint_limit_fraction": 0.0}
    assert episode_success(stats, 10.0) and episode_success(stats)
    assert not episode_success({**stats, "peak_joint_accel": 10.5}, 10.0)
    assert not episode_success({**stats, "joint_limit_fraction": 0.01}, 10.0)
    assert episode_success({**stats, "peak_joint_accel": 10.5})             # v1 does not check it
    assert gym.make(ENV_ID_V2, **FAST).unwrapped.task.success_joint_accel == 10.0
    assert gym.make(ENV_ID, **FAST).unwrapped.task.success_joint_accel is None


def test_failure_causes_name_each_missed_criterion_and_only_a_success_has_none(env):
    stats = {"coverage": 0.99, "force_in_band_fraction": 1.0, "arm_collision_fraction": 0.0,
             "self_collision_fraction": 0.0, "obstacle_touch_steps": 0, "obstacle_shift": 0.0,
             "peak_joint_accel": 4.0, "joint_limit_fraction": 0.0}
    assert failure_causes(stats, 10.0) == ()
    missed = {**stats, "coverage": 0.9, "obstacle_shift": 0.006, "self_collision_fraction": 0.1,
              "peak_joint_accel": float("nan")}
    assert failure_causes(missed, 10.0) == ("coverage", "self-collision", "cup", "joint acceleration")
    assert failure_causes(missed) == ("coverage", "self-collision", "cup")
    for seed, cup in ((0, False), (3, True)):          # seed 3: the imitation's approach runs into the cup
        env.reset(seed=seed)
        info = env.step(np.zeros(env.action_space.shape, np.float32))[4]
        assert info["is_success"] == (info["failure_causes"] == ())
        assert ("cup" in info["failure_causes"]) == cup == (info["obstacle_touch_steps"] > 0)


def test_a_refined_dmp_with_its_sweep_is_the_imitation_of_a_new_env(env, tmp_path):
    env.reset(seed=3)
    base = env.unwrapped
    action = np.zeros(env.action_space.shape)
    action[_slices(env)["sweep_x"]] = 0.5
    theta = base.action_to_params(action)
    path = tmp_path / "dmp.json"
    save_dmp(base.policy_dmp(theta), path)
    reloaded = gym.make(ENV_ID_V2, dmp=str(path), **FAST)
    reloaded.reset(seed=3)
    again = reloaded.unwrapped
    np.testing.assert_allclose(again.task.imitation_path(again.context), base.rollout_path(theta), atol=1e-9)


def test_bad_arguments_raise_clear_errors():
    with pytest.raises(ValueError, match="version"):
        gym.make(ENV_ID, version=4)
    with pytest.raises(ValueError, match="start, end"):
        covering_sweep(2.0, 1.0, 3)
    dmp = gym.make(ENV_ID, **FAST).unwrapped.dmp
    with pytest.raises(ValueError, match="covering sweep"):
        sweep_directions(dmp, ("periodic",))
    with pytest.raises(ValueError, match="via points"):
        gym.make(ENV_ID_V2, dmp=dmp.with_sweep(Sweep.uniform(2.0, 4.0, 3, 3)), **FAST)
    with pytest.raises(ValueError, match="max_shift"):
        gym.make(STEP_ID_V2, max_shift=(0.06, -0.01, 0.02), **FAST)


def test_the_step_twin_runs_the_v2_task_and_its_coupling_travels():
    # 3 IK iterations per control step instead of 30: the commanded shift read here is the same to 0.1 mm
    env = gym.make(STEP_ID_V2, obstacle=False, n_periods=1, control_rate=50.0, ik_iterations=3)
    assert env.unwrapped.wiping.task_version.version == 2
    np.testing.assert_allclose(env.unwrapped.max_shift, [0.06, 0.06, 0.02])
    shifts = []
    for action in (np.zeros(3, np.float32), np.array([1.0, 0.0, 0.0], np.float32)):
        obs, _ = env.reset(seed=7)
        positions, done = [], False
        while not done:
            obs, _, terminated, truncated, info = env.step(action)
            positions.append(obs[3])
            done = terminated or truncated
        shifts.append(np.mean(positions[len(positions) // 2:]))
    assert 0.5 * 0.06 < shifts[1] - shifts[0] < 1.2 * 0.06
    assert isinstance(info["is_success"], bool)


@pytest.mark.parametrize("seed", [0, pytest.param(5, marks=pytest.mark.slow)])        # seed 5: in the slow set
def test_cheap_strategies_lose_to_the_imitation(seed):
    """Gaming probes on v2 (full length, a context without the cup): holding still on the patch, pressing and
    lifting on a grid, hovering above the table, and uniformly random actions all score below action 0."""
    import probes

    env = gym.make(ENV_ID_V2)
    options = {"obstacle": 0}
    env.reset(seed=seed, options=options)
    base = env.unwrapped
    imitation, _ = base.run_path(base.task.imitation_path(base.context))
    paths = {"hold": probes.hold_still(base), "press_lift": probes.press_lift_grid(base),
             "hover": probes.hold_still(base, depth=-0.05)}
    for name, path in paths.items():
        reward, info = base.run_path(path)
        assert reward < imitation - 0.1, name
    action = np.random.default_rng(seed).uniform(-1, 1, env.action_space.shape).astype(np.float32)
    env.reset(seed=seed, options=options)
    _, reward, _, _, info = env.step(action)
    assert reward < imitation - 0.1 and info["jerk_ratio"] > 3.0
