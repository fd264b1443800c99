"""The wiping env's settings as data (rdmp_gym.envs.tasks.wiping.settings) and the checks of contexts given to
``reset``."""

import inspect
import json
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import rdmp_gym.envs  # noqa: F401  (registers the envs)
from rdmp_gym.envs import ENV_ID_V2, CupClearance
from rdmp_gym.envs.tasks.wiping.context import ContextSpec
from rdmp_gym.envs.tasks.wiping.force_learning import ForceProfileSettings
from rdmp_gym.envs.tasks.wiping.settings import (
    ENV_KWARGS,
    ContextConfig,
    EnvConfig,
    ForceConfig,
    RenderConfig,
    SettingTypeError,
    TaskConfig,
    TimingConfig,
)

from rdmp_gym import RhythmicDMP, wiping_demonstration

#: ArmarWipeEnv's keyword arguments and their defaults, as its signature gave them when the settings became data.
TODAY = {
    "style": 1, "demonstration": None, "dmp": None, "n_periodic": 40, "n_transient": 40, "fit_method": "trajectory",
    "groups": None, "scales": None, "n_periods": None, "duration": None, "control_rate": 100.0, "frame_skip": None,
    "timestep": None, "target_force": 18.0, "force_band": (5.0, 60.0), "force_sigma": 6.0, "reward_weights": None,
    "coverage_timing": "end",
    "adaptation": True, "admittance_gain": 0.02, "force_learning": False, "context_ranges": None, "obstacle": True,
    "obstacle_probability": 0.75, "cell_size": 0.01, "wear_rate": 2.0e-3, "penetration_limit": 0.005,
    "limit_margin": 0.02, "ik_tolerance": (0.005, float(np.deg2rad(5.0))), "max_joint_speed": None, "xml_file": None,
    "render_mode": None, "width": 480, "height": 480, "camera": "front", "record_frames": False, "frame_stride": 4,
    "version": 3, "cup_clearance": None, "robot": "armar3",
}

#: The context rules of ArmarWipe-v2 on the packaged table (cup radius 3.5 cm; the pad's half-diagonal + 1 cm).
V2_SPEC = {"table_extent": (-0.14, 0.36, -0.45, 0.45), "obstacle_radius": 0.035,
           "patch_clearance": float(np.hypot(0.035, 0.05)) + 0.01, "near_patch": True}


# ---------------------------------------------------------------------------------------------- defaults
def test_from_kwargs_with_todays_defaults_is_the_default_config():
    assert ENV_KWARGS == tuple(TODAY)                    # the env's keywords, in the order of its signature
    assert EnvConfig.from_kwargs(**TODAY) == EnvConfig()
    assert EnvConfig().to_kwargs() == TODAY
    assert EnvConfig().robot == "armar3"


def test_the_defaults_are_the_envs_signature():
    from rdmp_gym.envs.tasks.wiping.env import ArmarWipeEnv

    params = inspect.signature(ArmarWipeEnv.__init__).parameters
    named = [name for name in ENV_KWARGS if name in params]
    if not named:
        pytest.skip("the env takes its settings as an EnvConfig")
    defaults = EnvConfig().to_kwargs()
    for name in named:
        assert params[name].default == defaults[name], name
    keywords = [name for name, p in params.items() if name not in ("self", "config")
                and p.kind in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD)]
    assert set(keywords) <= set(ENV_KWARGS)             # every keyword of the env is a setting


def test_unknown_keyword_is_named():
    with pytest.raises(TypeError, match="colour"):
        EnvConfig.from_kwargs(colour="red")
    with pytest.raises(TypeError, match="target_forse"):
        EnvConfig().replace(target_forse=10.0)


def test_replace_changes_only_what_is_given_and_validates():
    config = EnvConfig.from_kwargs(version=2, target_force=15.0, control_rate=50, robot="armar3")
    assert config.task.version == 2 and config.force.target_force == 15.0 and config.timing.control_rate == 50.0
    assert config.force.force_band == (5.0, 60.0) and config.task == TaskConfig(version=2)
    with pytest.raises(ValueError, match="target_force"):
        config.replace(force_band=(20.0, 60.0))


# ---------------------------------------------------------------------------------------------- meaning
@pytest.mark.parametrize("kwargs, name", [
    ({"target_force": 70.0}, "target_force"),                     # above the band: success impossible
    ({"target_force": 4.0}, "target_force"),                      # below it
    ({"force_band": (20.0, 60.0)}, "target_force"),               # the default target outside a given band
    ({"cell_size": 1.0}, "cell_size"),                            # one cell: coverage meaningless
    ({"cell_size": 0.06}, "cell_size"),                           # above half the smallest drawable patch (10 cm)
    ({"cell_size": 0.02, "context_ranges": {"patch_size": (0.03, 0.1)}}, "cell_size"),
    ({"cup_clearance": 1.0}, "cup_clearance"),                    # pushes the sponge off the patch
    ({"cup_clearance": CupClearance(margin=0.2)}, "cup_clearance"),
    ({"limit_margin": 5.0}, "limit_margin"),                      # every step "at the limit"
    ({"limit_margin": 0.5}, "limit_margin"),
    ({"control_rate": 2.0}, "control_rate"),                      # every action unreachable
    ({"control_rate": 1000.0}, "control_rate"),                   # above the physics rate (500 Hz)
    ({"control_rate": 300.0, "timestep": 0.005}, "control_rate"),  # above the given physics rate (200 Hz)
    ({"frame_skip": 30}, "frame_skip"),                           # 16.7 Hz at 2 ms
    ({"obstacle": 0.3}, "obstacle"),                              # a fraction is not a presence
    ({"obstacle": 1}, "obstacle"),
    ({"obstacle_probability": 1.5}, "obstacle_probability"),
    ({"admittance_gain": -0.02}, "admittance_gain"),
])
def test_meaningless_settings_name_the_argument(kwargs, name):
    with pytest.raises(ValueError, match=name):
        EnvConfig.from_kwargs(**kwargs)


@pytest.mark.parametrize("kwargs, name", [
    # today's checks, kept
    ({"version": 9}, "version"), ({"version": True}, "version"), ({"style": 7}, "style"), ({"style": True}, "style"),
    ({"fit_method": "magic"}, "fit_method"), ({"limit_margin": -0.1}, "limit_margin"),
    ({"control_rate": 0.0}, "control_rate"), ({"frame_skip": 0}, "frame_skip"), ({"frame_skip": True}, "frame_skip"),
    ({"timestep": -0.001}, "timestep"), ({"force_band": (30.0, 10.0)}, "force_band"),
    ({"force_band": (-1.0, 10.0)}, "force_band"), ({"force_band": (5.0, float("inf"))}, "force_band"),
    ({"force_band": (5.0,)}, "force_band"), ({"target_force": 0.0}, "target_force"),
    ({"force_sigma": 0.0}, "force_sigma"), ({"reward_weights": {"coverage": -1.0}}, "reward_weights"),
    ({"reward_weights": {"typo": 1.0}}, "reward_weights"), ({"render_mode": "ansi"}, "render_mode"),
    ({"context_ranges": {"table_height": (0.0, 1.0)}}, "context_ranges"),
    ({"context_ranges": {"nonsense": (0.0, 1.0)}}, "context_ranges"),
    ({"context_ranges": {"obstacle": (0.0, 1.0)}}, "context_ranges"),
    ({"obstacle": "yes"}, "obstacle"), ({"wear_rate": 0.0}, "wear_rate"), ({"scales": {"periodic": -1.0}}, "scales"),
    ({"scales": {"approach": 0.0}}, "scales"), ({"ik_tolerance": (0.005,)}, "ik_tolerance"),
    ({"ik_tolerance": (0.0, 0.1)}, "ik_tolerance"), ({"max_joint_speed": float("nan")}, "max_joint_speed"),
    ({"penetration_limit": 0.0}, "penetration_limit"), ({"cup_clearance": 0.0}, "cup_clearance"),
    ({"cup_clearance": True}, "cup_clearance"), ({"cup_clearance": "1cm"}, "cup_clearance"),
    ({"duration": 0.0}, "duration"), ({"n_periods": -1.0}, "n_periods"), ({"frame_stride": 0}, "frame_stride"),
    # types
    ({"n_periodic": 40.5}, "n_periodic"), ({"n_transient": "40"}, "n_transient"), ({"width": 1.5}, "width"),
    ({"height": None}, "height"), ({"camera": 3}, "camera"), ({"record_frames": "yes"}, "record_frames"),
    ({"adaptation": 1}, "adaptation"), ({"force_learning": "on"}, "force_learning"),
    ({"groups": 3}, "groups"), ({"groups": ()}, "groups"), ({"scales": [0.1]}, "scales"),
    ({"reward_weights": [1.0]}, "reward_weights"), ({"context_ranges": {"patch_size": "wide"}}, "context_ranges"),
    ({"dmp": 3}, "dmp"), ({"demonstration": "demo.npz"}, "demonstration"), ({"xml_file": 3}, "xml_file"),
    ({"robot": ""}, "robot"), ({"target_force": "18"}, "target_force"),
])
def test_bad_settings_name_the_argument(kwargs, name):
    with pytest.raises(ValueError, match=name):               # a SettingTypeError is a ValueError too
        EnvConfig.from_kwargs(**kwargs)


def test_a_wrong_type_is_a_type_error_and_a_value_error():
    with pytest.raises(SettingTypeError, match="obstacle") as error:
        ContextConfig(obstacle=0.3)
    assert isinstance(error.value, TypeError) and isinstance(error.value, ValueError)


def test_dmp_and_demonstration_exclude_each_other():
    demo = wiping_demonstration(style=1, rng=0)
    with pytest.raises(ValueError, match="dmp"):
        TaskConfig(demonstration=demo, dmp="dmp.json")


def test_valid_edge_settings_are_accepted():
    EnvConfig.from_kwargs(control_rate=20.0, cell_size=0.05, cup_clearance=0.05, limit_margin=0.49,
                          target_force=5.5, frame_skip=25, obstacle=np.bool_(False), n_periodic=40.0)
    EnvConfig.from_kwargs(cell_size=0.01, context_ranges={"patch_size": (0.02, 0.1)})   # two cells a side


def test_check_robot_bounds_the_limit_margin_by_the_narrowest_joint():
    ranges = np.array([[-1.0, 1.0], [-0.2, 0.2], [0.0, 3.0]])        # narrowest 0.4 rad: margin <= 0.1
    EnvConfig.from_kwargs(limit_margin=0.1).check_robot(ranges)
    with pytest.raises(ValueError, match="limit_margin"):
        EnvConfig.from_kwargs(limit_margin=0.11).check_robot(ranges)
    with pytest.raises(ValueError, match="joint_ranges"):
        EnvConfig().check_robot(np.array([0.0, 1.0]))


def test_frame_skip_for_a_model_follows_the_envs_rule():
    assert TimingConfig().frame_skip_for(0.002) == 5
    assert TimingConfig(control_rate=30.0).frame_skip_for(0.002) == round(1.0 / (30.0 * 0.002))
    assert TimingConfig(control_rate=100.0, timestep=0.001).frame_skip_for(0.002) == 10
    assert TimingConfig(frame_skip=10).frame_skip_for(0.002) == 10
    with pytest.raises(ValueError, match="control_rate"):
        TimingConfig(control_rate=200.0).frame_skip_for(0.01)          # the model's physics runs at 100 Hz
    with pytest.raises(ValueError, match="frame_skip"):
        TimingConfig(frame_skip=10).frame_skip_for(0.01)               # 10 Hz


# ---------------------------------------------------------------------------------------------- JSON
def test_json_round_trip_is_exact(tmp_path):
    config = EnvConfig.from_kwargs(
        version=2, style=3, dmp=Path("runs/a/dmp.json"), n_periodic=30, groups=["periodic", "sweep"],
        scales={"periodic": np.float32(0.15)}, n_periods=5.5, control_rate=50, timestep=0.001,
        target_force=15.0, force_band=np.array([4.0, 40.0]), reward_weights={"coverage": 2, "smoothness": 0.1},
        adaptation=False, admittance_gain=0.03, force_learning=ForceProfileSettings(n_basis=12, gain=0.2),
        context_ranges={"patch_size": (0.12, np.array([0.2, 0.18])), "table_tilt": (-0.01, 0.01)},
        obstacle_probability=0.5, cell_size=0.02, ik_tolerance=[0.004, 0.08], cup_clearance=CupClearance(margin=0.02),
        xml_file=Path("scene.xml"), render_mode="rgb_array", width=64, height=48, camera=None, record_frames=True)
    path = tmp_path / "env_config.json"
    config.save(path)
    loaded = EnvConfig.load(path)
    assert loaded == config
    assert loaded.to_kwargs() == config.to_kwargs()
    assert loaded.task.ik_tolerance == (0.004, 0.08) and loaded.task.groups == ("periodic", "sweep")
    assert loaded.force.force_band == (4.0, 40.0) and loaded.task.scales == {"periodic": float(np.float32(0.15))}
    assert loaded.context.ranges["patch_size"] == (0.12, (0.2, 0.18))
    assert loaded.task.dmp == str(Path("runs/a/dmp.json")) and loaded.xml_file == "scene.xml"
    assert json.loads(path.read_text())["task"]["cup_clearance"]["margin"] == 0.02
    assert EnvConfig.from_dict(EnvConfig().to_dict()) == EnvConfig()
    plain = EnvConfig.from_kwargs(cup_clearance=0.01, force_learning=True)
    assert EnvConfig.from_dict(json.loads(json.dumps(plain.to_dict()))) == plain


def test_json_refuses_live_objects_by_name():
    demo = wiping_demonstration(style=1, rng=0)
    with pytest.raises(ValueError, match="demonstration"):
        EnvConfig.from_kwargs(demonstration=demo).to_dict()
    dmp = RhythmicDMP.fit(demo, n_periodic=10, n_transient=10)
    with pytest.raises(ValueError, match="dmp"):
        EnvConfig.from_kwargs(dmp=dmp).save("unused.json")
    from rdmp_gym.envs.robots import get_robot

    robot = get_robot("armar3")
    assert EnvConfig.from_kwargs(robot=robot).robot is robot
    with pytest.raises(ValueError, match=r"robot.*register"):
        EnvConfig.from_kwargs(robot=robot).to_dict()


def test_from_dict_names_unknown_entries():
    data = EnvConfig().to_dict()
    with pytest.raises(ValueError, match="colour"):
        EnvConfig.from_dict({**data, "colour": 1})
    with pytest.raises(ValueError, match="target_forse"):
        EnvConfig.from_dict({**data, "force": {"target_forse": 10.0}})
    with pytest.raises(ValueError, match="format_version"):
        EnvConfig.from_dict({**data, "format_version": 99})
    with pytest.raises(ValueError, match="cup_clearance"):
        EnvConfig.from_dict({**data, "task": {"cup_clearance": {"margn": 0.01}}})
    assert EnvConfig.from_dict({"force": {"target_force": 10.0}}) == EnvConfig.from_kwargs(target_force=10.0)


def test_groups_are_validated_on_their_own():
    assert ForceConfig(target_force=10.0).target_force == 10.0
    assert RenderConfig(render_mode="depth_array").render_mode == "depth_array"
    with pytest.raises(ValueError, match="task"):
        EnvConfig(task=ForceConfig())


# ---------------------------------------------------------------------------------------------- given contexts
@pytest.mark.parametrize("seed", range(8))
def test_obstacle_position_without_obstacle_is_an_error_whatever_the_seed(seed):
    spec = ContextSpec(**V2_SPEC)
    with pytest.raises(ValueError, match="obstacle_position is given without obstacle"):
        spec.sample(np.random.default_rng(seed), {"obstacle_position": [0.1, -0.2]})
    with pytest.raises(ValueError, match="obstacle = 0"):
        spec.sample(np.random.default_rng(seed), {"obstacle": 0, "obstacle_position": [0.1, -0.2]})


@pytest.mark.parametrize("options", [
    {"obstacle": 0.3}, {"obstacle": 0.7},
    {"context": [0, 0, 0, 0, 0, 0.12, 0.12, -0.07, 0.22, 0.08, 0.5, 0.15, -0.25]},
])
def test_obstacle_is_zero_or_one(options):
    with pytest.raises(ValueError, match=r"obstacle expects 0 .* or 1"):
        ContextSpec(**V2_SPEC).sample(np.random.default_rng(0), options)


def test_a_given_cup_on_the_sponge_start_is_refused():
    spec = ContextSpec(**V2_SPEC)
    options = {"patch_centre": [0.0, 0.0], "patch_size": [0.12, 0.12], "sponge_start": [-0.05, 0.25, 0.1],
               "obstacle": 1, "obstacle_position": [-0.05, 0.22]}
    with pytest.raises(ValueError, match=r"obstacle_position .* sponge start"):
        spec.sample(np.random.default_rng(0), options)
    vector = np.array([0, 0, 0, 0, 0, 0.12, 0.12, -0.05, 0.25, 0.1, 1.0, -0.05, 0.22])
    with pytest.raises(ValueError, match="sponge start"):
        spec.sample(np.random.default_rng(0), {"context": vector})
    # ArmarWipe-v1's 1 cm clearance: the cup's radius + 1 cm from the start
    v1 = ContextSpec(table_extent=V2_SPEC["table_extent"], obstacle_radius=0.035)
    with pytest.raises(ValueError, match="sponge start"):
        v1.sample(np.random.default_rng(0), {**options, "obstacle_position": [-0.05, 0.21]})


@pytest.mark.parametrize("position", [[0.02, 0.03], [0.34, 0.3]])          # on the patch, off the table
def test_a_given_cup_on_the_patch_or_off_the_table_is_refused(position):
    options = {"patch_centre": [0.0, 0.0], "patch_size": [0.12, 0.12], "obstacle": 1, "obstacle_position": position}
    with pytest.raises(ValueError, match="obstacle_position"):
        ContextSpec(**V2_SPEC).sample(np.random.default_rng(0), options)


def test_a_valid_given_cup_is_placed_as_given():
    spec = ContextSpec(**V2_SPEC)
    options = {"patch_centre": [0.0, 0.0], "patch_size": [0.12, 0.12], "sponge_start": [-0.05, 0.25, 0.1],
               "obstacle": 1, "obstacle_position": [0.05, -0.2]}
    for seed in range(5):
        context = spec.sample(np.random.default_rng(seed), options)
        assert context.obstacle and np.array_equal(context.obstacle_position, [0.05, -0.2])
    # presence without a position still draws the cup in the corridor
    assert spec.sample(np.random.default_rng(0), {"obstacle": 1, "sponge_start": [-0.05, 0.25, 0.1]}).obstacle


@pytest.mark.parametrize("near_patch", [False, True])
def test_drawn_contexts_replay_exactly_through_the_options(near_patch):
    """Every drawn context, given back (float64 or as the float32 observation), is accepted and reproduced."""
    spec = ContextSpec(**{**V2_SPEC, "near_patch": near_patch,
                          "patch_clearance": V2_SPEC["patch_clearance"] if near_patch else 0.01})
    cups = 0
    for seed in range(300):
        drawn = spec.sample(np.random.default_rng(seed))
        cups += drawn.obstacle
        vector = drawn.vector()
        assert np.array_equal(spec.sample(np.random.default_rng(seed + 1), {"context": vector}).vector(), vector)
        observed = vector.astype(np.float32)
        replay = spec.sample(np.random.default_rng(seed + 1), {"context": observed}).vector()
        assert np.array_equal(replay, observed.astype(np.float64))
        if drawn.obstacle:
            again = spec.sample(np.random.default_rng(seed), {"obstacle": 1,
                                                               "obstacle_position": drawn.obstacle_position})
            assert np.array_equal(again.vector(), vector)
    assert cups > 50


@pytest.mark.filterwarnings("ignore:.*out of date")
def test_the_env_checks_given_cups():
    env = gym.make(ENV_ID_V2)
    try:
        options = {"patch_centre": [0.0, 0.0], "patch_size": [0.12, 0.12], "sponge_start": [-0.05, 0.25, 0.1]}
        obs, _ = env.reset(seed=0, options={**options, "obstacle": 1, "obstacle_position": [0.05, -0.2]})
        assert obs[10] == 1.0 and obs[11:13] == pytest.approx([0.05, -0.2])
        for seed in (0, 1, 2):
            with pytest.raises(ValueError, match="obstacle_position is given without obstacle"):
                env.reset(seed=seed, options={**options, "obstacle_position": [0.05, -0.2]})
        with pytest.raises(ValueError, match="sponge start"):
            env.reset(seed=0, options={**options, "obstacle": 1, "obstacle_position": [-0.05, 0.2]})
        with pytest.raises(ValueError, match="obstacle expects"):
            env.reset(seed=0, options={"obstacle": 0.3})
    finally:
        env.close()
