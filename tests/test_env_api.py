"""Gymnasium/SB3 contract of rdmp_gym/ArmarWipe-v1: spaces, checkers, reward terms, determinism, bad input."""

import gymnasium as gym
import numpy as np
import pytest
import rdmp_gym.envs  # noqa: F401  (registers the env)
from rdmp_gym.envs import DEPRECATED_ENV_ID, ENV_ID, TERMS, ArmarWipeEnv
from rdmp_gym.envs.rhythmic_env import RhythmicTaskEnv
from rdmp_gym.envs.tasks.wiping.scene import TablePose, table_frame
from rdmp_gym.envs.tasks.wiping.task import WipingTask

from rdmp_gym import wiping_demonstration

FAST = {"n_periods": 1.0}


@pytest.fixture(scope="module")
def env():
    environment = gym.make(ENV_ID, **FAST)
    yield environment
    environment.close()


def zero(env):
    return np.zeros(env.action_space.shape, dtype=np.float32)


def test_registered_and_spaces(env):
    assert ENV_ID in gym.registry
    assert gym.registry[ENV_ID].max_episode_steps is None
    u = env.unwrapped
    assert isinstance(u, RhythmicTaskEnv) and isinstance(u.task, WipingTask)
    assert env.action_space.dtype == np.float32
    assert np.all(env.action_space.low == -1) and np.all(env.action_space.high == 1)
    # the DMP's parameters plus the one-dimensional approach lift (last)
    assert env.action_space.shape == (u.dmp.layout.size(("periodic", "transient", "initial", "amplitude")) + 1,)
    space = env.observation_space
    assert space.dtype == np.float32 and space.shape == (13,)
    assert np.all(np.isfinite(space.low)) and np.all(np.isfinite(space.high))


def test_gymnasium_and_sb3_checkers():
    from gymnasium.utils.env_checker import check_env as gym_check
    from stable_baselines3.common.env_checker import check_env as sb3_check

    environment = gym.make(ENV_ID, **FAST)
    gym_check(environment.unwrapped, skip_render_check=True)
    sb3_check(environment.unwrapped, warn=True)
    environment.close()


def test_step_contract_and_reward_terms(env):
    obs, info = env.reset(seed=3, options={"obstacle": 0})
    assert env.observation_space.contains(obs)
    obs2, reward, terminated, truncated, info = env.step(zero(env))
    assert terminated is True and truncated is False
    assert type(reward) is float
    assert np.array_equal(obs, obs2)
    terms = info["reward_terms"]
    assert tuple(terms) == TERMS
    assert reward == sum(terms.values())
    cost = info["cost_trace"]
    assert cost.dtype == np.float64 and cost.shape == (env.unwrapped.n_steps,)
    assert cost.sum() == pytest.approx(-reward, abs=1e-9)
    assert 0.5 < reward < 1.5                                    # O(1)
    for key in ("coverage", "force_mean", "force_in_band_fraction", "valid", "unstable", "params", "is_success",
                "impact_force", "jerk_ratio", "obstacle_shift", "penetration"):
        assert key in info
    assert type(info["is_success"]) is bool
    assert info["jerk_ratio"] == pytest.approx(1.0)                 # action 0 is the imitation
    assert info["reward_terms"]["smoothness"] == pytest.approx(0.0, abs=1e-9)  # imitation_path: same path to round-off
    assert info["valid"] is True and info["unstable"] is False
    assert info["params"] == pytest.approx(env.unwrapped.action_map.theta0)


def test_seeded_determinism_is_bit_identical(env):
    action = np.random.default_rng(1).uniform(-1, 1, env.action_space.shape).astype(np.float32)
    results = []
    for _ in range(2):
        obs, _ = env.reset(seed=11)
        results.append((obs, *env.step(action)))
    (o1, p1, r1, _, _, i1), (o2, p2, r2, _, _, i2) = results
    assert np.array_equal(o1, o2) and np.array_equal(p1, p2) and r1 == r2
    assert np.array_equal(i1["cost_trace"], i2["cost_trace"])
    assert np.array_equal(i1["force_trace"], i2["force_trace"])
    assert i1["reward_terms"] == i2["reward_terms"]
    o3, _ = env.reset(seed=12)
    assert not np.array_equal(o1, o3)


def test_action_param_mapping(env):
    u = env.unwrapped
    env.reset(seed=0)
    assert u.action_to_params(zero(env)) == pytest.approx(u.dmp.get_params(u.task.groups))
    a = np.random.default_rng(2).uniform(-1, 1, env.action_space.shape).astype(np.float32)
    a[-1] = 0.0                 # the approach dimension: params_to_action expresses every theta without it
    assert u.params_to_action(u.action_to_params(a)) == pytest.approx(a, abs=1e-5)
    b = np.random.default_rng(3).uniform(-1, 1, env.action_space.shape).astype(np.float32)
    theta = u.action_to_params(b)
    # with the approach moved, the same theta needs no approach (may lie beyond the box: the map's own inverse)
    assert u.action_map.to_params(u.params_to_action(theta)) == pytest.approx(theta, rel=1e-5, abs=1e-6)
    weights = u.action_time_weights()
    assert weights.shape == (u.n_steps, env.action_space.shape[0])
    assert weights.min() >= 0.0 and weights.max() <= 1.0
    # the transient weights act early, the periodic ones late
    part = u.action_map.slices
    early, late = slice(0, 20), slice(-20, None)
    assert weights[early, part["transient:0"]].sum() > weights[early, part["periodic"]].sum()
    assert weights[late, part["periodic"]].sum() > weights[late, part["transient:0"]].sum()
    assert weights[0, -1] == 0.0 and weights[:, -1].max() == 1.0 and weights[late, -1].sum() == 0.0   # approach


def test_bad_actions_raise(env):
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action"):
        env.unwrapped.step(np.zeros(3, dtype=np.float32))
    bad = zero(env)
    bad[5] = np.nan
    with pytest.raises(ValueError, match="action"):
        env.unwrapped.step(bad)
    with pytest.raises(ValueError, match="action"):
        env.unwrapped.action_to_params(np.full(env.action_space.shape, np.inf))


def test_invalid_parameters_get_a_graded_penalty_without_simulation():
    environment = gym.make(ENV_ID, scales={"initial": 2.0}, **FAST)   # r0 scale 2 x r0: a = -1 gives r0 < 0
    u = environment.unwrapped
    environment.reset(seed=0)
    index = u.action_map.r0_index[0]
    rewards = []
    for value in (-0.6, -0.9):
        action = np.zeros(environment.action_space.shape, dtype=np.float32)
        action[index] = value
        _, reward, terminated, truncated, info = environment.step(action)
        assert terminated is True and truncated is False
        assert info["valid"] is False and info["invalid_reason"] == "r0"
        assert info["failure_causes"] == ("invalid",) and info["is_success"] is False
        assert info["steps"] == 0
        assert reward == sum(info["reward_terms"].values()) and reward <= -1.0
        assert info["cost_trace"].sum() == pytest.approx(-reward)
        rewards.append(reward)
    assert rewards[1] < rewards[0]                                   # graded: worse violation, lower reward
    environment.close()


def test_out_of_reach_paths_are_invalid(env):
    u = env.unwrapped
    env.reset(seed=0)
    path = np.zeros((u.n_steps, 3))
    path[:, 0] = 5.0                                                 # 5 m out: outside the workspace
    reward, info = u.run_path(path)
    assert info["valid"] is False and info["invalid_reason"] == "workspace"
    assert reward == pytest.approx(-2.0)                              # severity capped at 1
    # an IK that cannot meet its tolerance marks the path unreachable (graded by the residual)
    strict = gym.make(ENV_ID, ik_tolerance=(1e-12, 1e-12), **FAST).unwrapped
    strict.reset(seed=0)
    reward, info = strict.run_path(strict.rollout_path(strict.action_map.theta0))
    assert info["valid"] is False and info["invalid_reason"] == "unreachable"
    assert -2.0 <= reward <= -1.0


def test_reset_options(env):
    obs, _ = env.reset(seed=0, options={"table_height": 0.01, "patch_centre": [0.02, -0.01],
                                        "patch_size": [0.1, 0.08], "sponge_start": [-0.05, 0.1, 0.08]})
    assert obs[0] == pytest.approx(0.01)
    assert obs[3:5] == pytest.approx([0.02, -0.01])
    assert obs[5:7] == pytest.approx([0.1, 0.08])
    assert obs[7:10] == pytest.approx([-0.05, 0.1, 0.08])
    assert obs[10] in (0.0, 1.0)
    full = np.array([0, 0, 0, 0, 0, 0.12, 0.12, -0.07, 0.1, 0.08, 1.0, -0.05, 0.15])
    obs, _ = env.reset(seed=0, options={"context": full})
    assert obs == pytest.approx(full)
    u = env.unwrapped
    origin, rot = table_frame(u.task.parts, TablePose.of(u.context))
    cup = u.scene.data.qpos[u.task.parts.obstacle_qpos:u.task.parts.obstacle_qpos + 2]
    assert cup == pytest.approx((origin + rot @ np.array([-0.05, 0.15, 0.0]))[:2], abs=1e-6)
    # dirt lives on the table only: a patch over the near edge (x = -0.14) is refused
    with pytest.raises(ValueError, match="beyond the table"):
        env.reset(options={"patch_centre": [-0.15, 0.0], "patch_size": [0.12, 0.12]})
    # a cup off the table or on the patch is refused
    with pytest.raises(ValueError, match="obstacle_position"):
        env.reset(options={"patch_centre": [0.0, 0.0], "obstacle": 1, "obstacle_position": [0.02, 0.03]})
    no_cup = gym.make(ENV_ID, obstacle=False, **FAST)
    with pytest.raises(ValueError, match="obstacle=False"):
        no_cup.reset(options={"obstacle": 1})
    assert all(no_cup.reset(seed=s)[0][10] == 0.0 for s in range(5))
    with pytest.raises(ValueError, match="options"):
        env.reset(options={"table_height": 0.5})
    with pytest.raises(ValueError, match="options"):
        env.reset(options={"nonsense": 1})
    with pytest.raises(ValueError, match="options"):
        env.reset(options={"patch_size": [0.1]})


@pytest.mark.parametrize("kwargs, match", [
    ({"style": 7}, "style"),
    ({"fit_method": "magic"}, "fit_method"),
    ({"limit_margin": -0.1}, "limit_margin"),
    ({"duration": 0.5}, "duration"),
    ({"groups": ("periodic", "anchor")}, "groups"),
    ({"groups": ("bogus",)}, "groups"),
    ({"scales": {"periodic": -1.0}}, "scales"),
    ({"control_rate": 0.0}, "control_rate"),
    ({"frame_skip": 0}, "frame_skip"),
    ({"force_band": (30.0, 10.0)}, "force_band"),
    ({"reward_weights": {"coverage": -1.0}}, "reward_weights"),
    ({"reward_weights": {"typo": 1.0}}, "reward_weights"),
    ({"render_mode": "ansi"}, "render_mode"),
    ({"xml_file": "/nonexistent.xml"}, "xml_file"),
    ({"context_ranges": {"table_height": (0.0, 1.0)}}, "context_ranges"),
    ({"context_ranges": {"patch_centre": (-0.1, 0.0)}}, "context_ranges"),     # patches over the table edge
    ({"obstacle": "yes"}, "obstacle"),
    ({"wear_rate": 0.0}, "wear_rate"),
    ({"groups": ("periodic", "approach")}, "groups"),                          # the approach moves transient weights
    ({"scales": {"approach": 0.0}}, "scales"),
])
def test_bad_constructor_arguments(kwargs, match):
    with pytest.raises(ValueError, match=match):
        ArmarWipeEnv(**FAST, **kwargs)


def test_the_approach_dimension_lifts_the_approach_smoothly(env):
    """The approach dimension at +1 lifts the DMP's own path by the smooth bump (6 cm), leaves the start and
    the wiping untouched and needs no more joint acceleration than ARMAR-III allows (10 rad/s²)."""
    from rdmp_gym.envs.tasks.wiping.approach import lift_profile

    u = env.unwrapped
    env.reset(seed=0)
    a = zero(env)
    a[-1] = 1.0
    lift = u.rollout_path(u.action_to_params(a)) - u.rollout_path(u.action_map.theta0)
    target = 0.06 * lift_profile(u.times, u.dmp.transients[0].length)
    assert np.abs(lift[:, 2] - target).max() < 1e-3 and lift[:, 2].max() > 0.058
    assert np.abs(lift[:, :2]).max() < 1e-9                              # only the height moves
    assert np.abs(lift[0]).max() < 1e-9 and np.abs(lift[u.task.periodic]).max() < 1e-3
    _, _, _, _, info = env.step(a)
    assert info["valid"] and info["peak_joint_accel"] < 10.0 and info["jerk_ratio"] < 3.0


def test_variants_frame_skip_xml_groups_demonstration():
    u = gym.make(ENV_ID, frame_skip=10, **FAST).unwrapped
    assert u.frame_skip == 10 and u.control_rate == pytest.approx(50.0)
    default_xml = u.scene.xml_file
    v = gym.make(ENV_ID, xml_file=default_xml, groups=("periodic",), control_rate=50.0, **FAST).unwrapped
    assert v.frame_skip == 10
    assert v.action_space.shape == (v.dmp.layout.size("periodic"),)
    demo = wiping_demonstration(style=3, rng=5)
    w = gym.make(ENV_ID, demonstration=demo, n_periodic=20, n_transient=20, **FAST).unwrapped
    w.reset(seed=0)
    _, reward, *_ = w.step(np.zeros(w.action_space.shape, dtype=np.float32))
    assert reward > 0.5


def test_v0_is_deprecated():
    with pytest.warns(DeprecationWarning, match="ArmarWipe-v1"):
        old = gym.make(DEPRECATED_ENV_ID, **FAST)
    assert isinstance(old.unwrapped, ArmarWipeEnv) and old.unwrapped.task.obstacle is False
    assert gym.spec(ENV_ID).kwargs["obstacle"] is True


def test_render_and_record(tmp_path):
    environment = gym.make(ENV_ID, render_mode="rgb_array", width=96, height=64, n_periods=0.3, frame_stride=20)
    environment.reset(seed=0)
    frame = environment.render()
    assert frame.shape == (64, 96, 3) and frame.dtype == np.uint8 and frame.std() > 0
    out = environment.unwrapped.record_episode(np.zeros(environment.action_space.shape, np.float32),
                                               tmp_path / "episode.gif", fps=5)
    assert out[2] is True
    assert (tmp_path / "episode.gif").stat().st_size > 0
    assert len(environment.unwrapped.frames) >= 2
    environment.close()
    environment.close()
    recorder = gym.make(ENV_ID, record_frames=True, width=48, height=48, n_periods=0.3, frame_stride=25).unwrapped
    recorder.reset(seed=1)
    recorder.step(np.zeros(recorder.action_space.shape, np.float32))
    assert len(recorder.frames) == 1 + recorder.n_steps // 25 and recorder.frames[0].shape == (48, 48, 3)
    recorder.close()
