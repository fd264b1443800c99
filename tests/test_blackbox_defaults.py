"""The black-box wrapper's settings object, its defaults derived from a MuJoCo model, loose envs, time limits, the
task contract and video recording."""

from __future__ import annotations

import dataclasses

import gymnasium as gym
import mujoco
import numpy as np
import pytest
from rdmp_gym.envs.blackbox import (
    MODEL_RULES,
    BlackBoxSettings,
    RhythmicBlackBoxWrapper,
    env_defaults,
    make_blackbox,
)
from rdmp_gym.envs.contract import contract_of, metric_values

DT = 0.01


class LooseJoints(gym.Env):
    """Gymnasium's API but little else, as robosuite's ``GymWrapper``: ``metadata`` None, no spec, no ``dt``, no
    time limit; two joints under torques (unit inertia), the step's info says ``is_success`` (near the origin)."""

    metadata = None

    def __init__(self) -> None:
        self.action_space = gym.spaces.Box(-10.0, 10.0, (2,), np.float32)
        self.observation_space = gym.spaces.Box(-np.inf, np.inf, (4,), np.float64)
        self.q, self.qd = np.zeros(2), np.zeros(2)

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.q, self.qd = self.np_random.uniform(-0.05, 0.05, 2), np.zeros(2)
        return np.r_[self.q, self.qd], {}

    def step(self, action):
        self.qd = self.qd + DT * np.asarray(action, dtype=np.float64)
        self.q = self.q + DT * self.qd
        near = bool(np.linalg.norm(self.q) < 0.5)
        return np.r_[self.q, self.qd], -float(self.q @ self.q), False, False, {"is_success": near}


def read_joints(env):
    base = env.unwrapped
    return base.q.copy(), base.qd.copy()


LOOSE = {"joint_state": read_joints, "dt": DT, "p_gains": 400.0, "d_gains": 40.0, "posture": (0.0, 0.0),
         "period": 1.0, "amplitude": 0.05}


def zero_action_steps(env_id: str, seed: int) -> int:
    env = gym.make(env_id)
    env.reset(seed=seed)
    steps = 0
    while True:
        steps += 1
        if any(env.step(np.zeros(env.action_space.shape))[2:4]):
            env.close()
            return steps


def pattern_steps(env: RhythmicBlackBoxWrapper, seed: int) -> int:
    env.reset(seed=seed)
    return env.step(np.zeros(env.action_space.shape, np.float32))[4]["env_steps"]


@pytest.fixture(scope="module")
def pendulum():
    env = make_blackbox("InvertedPendulum-v5")
    yield env
    env.close()


@pytest.fixture(scope="module")
def hopper():
    env = make_blackbox("Hopper-v5")
    yield env
    env.close()


# ------------------------------------------------------------------ the settings object
def test_settings_are_one_frozen_validated_record():
    settings = BlackBoxSettings(p_gains=[5, 6], groups=["periodic"], duration=2)
    assert settings.p_gains == (5.0, 6.0) and settings.groups == ("periodic",) and settings.duration == 2.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        settings.duration = 3.0
    moved = BlackBoxSettings.build(settings, duration=4.0)
    assert moved.duration == 4.0 and moved.p_gains == (5.0, 6.0) and settings.duration == 2.0
    with pytest.raises(TypeError, match="p_gain: not a setting of the rhythmic black-box wrapper"):
        BlackBoxSettings.build(settings, p_gain=3.0)
    with pytest.raises(TypeError, match="settings: expected a BlackBoxSettings"):
        BlackBoxSettings.build({"p_gains": 3.0})


@pytest.mark.parametrize(("keyword", "value"), [
    ("duration", float("nan")), ("duration", float("inf")), ("duration", -1.0), ("duration", "4"),
    ("p_gains", -1.0), ("d_gains", [1.0, float("nan")]), ("period", 0.0), ("amplitude", 0.0), ("groups", []),
    ("n_periodic", 0), ("context_mask", [0, 1]), ("joint_state", "qpos"), ("controller", "torque"),
    ("dt", float("nan")), ("posture", [0.0, float("inf")]), ("scales", [0.5])])
def test_a_bad_setting_is_refused_by_name(keyword, value):
    with pytest.raises(ValueError, match=f"^{keyword}: "):
        BlackBoxSettings(**{keyword: value})


def test_the_wrapper_takes_a_settings_object_and_overrides():
    settings = BlackBoxSettings(**LOOSE, duration=0.5)
    env = RhythmicBlackBoxWrapper(LooseJoints(), settings, duration=0.3)
    assert env.settings.duration == 0.3 and env.n_steps == 30 and env.settings.p_gains == 400.0
    with pytest.raises(ValueError, match=r"^duration: "):
        RhythmicBlackBoxWrapper(LooseJoints(), settings, duration=float("nan"))
    swimmer = make_blackbox("Swimmer-v5", settings=BlackBoxSettings(duration=2.0), groups=("amplitude",))
    assert swimmer.n_steps == 50 and swimmer.action_space.shape == (2,)
    swimmer.close()


# ------------------------------------------------------------------ loose envs and time limits
def test_a_loose_env_works_with_duration_and_a_joint_state_reader():
    with pytest.raises(ValueError, match=r"duration: the env has no time limit .* pass duration="):
        RhythmicBlackBoxWrapper(LooseJoints(), **LOOSE)
    env = RhythmicBlackBoxWrapper(LooseJoints(), **LOOSE, duration=1.0)
    assert env.metadata == {} and env.n_steps == 100 and env.env_name == "LooseJoints"
    env.reset(seed=0)
    _, reward, terminated, _, info = env.step(np.zeros(env.action_space.shape, np.float32))
    assert terminated and np.isfinite(reward) and info["env_steps"] == 100 and info["tracking_rmse"] < 0.05
    assert info["is_success"] is True and env.task_contract().has_success


def test_a_time_limit_shorter_than_the_duration_is_refused():
    limited = gym.wrappers.TimeLimit(LooseJoints(), max_episode_steps=50)
    with pytest.raises(ValueError, match="duration: 1 s is 100 env steps, more than the env's time limit of 50 steps"):
        RhythmicBlackBoxWrapper(limited, **LOOSE, duration=1.0)
    assert RhythmicBlackBoxWrapper(limited, **LOOSE).n_steps == 50          # the limit is the default duration
    inner = gym.wrappers.TimeLimit(gym.make("InvertedPendulum-v5"), max_episode_steps=20)   # below the spec's 1000
    assert RhythmicBlackBoxWrapper.time_limit(inner) == 20
    with pytest.raises(ValueError, match="time limit of 20 steps"):
        RhythmicBlackBoxWrapper(inner, duration=2.0)
    inner.close()


# ------------------------------------------------------------------ defaults derived from the model
def test_known_envs_keep_their_published_defaults():
    swimmer = make_blackbox("Swimmer-v5")
    assert swimmer.controller.p_gains.tolist() == [10.0, 10.0] and swimmer.controller.d_gains.tolist() == [0.5, 0.5]
    assert swimmer.dmp.period == pytest.approx(1.0 / 0.62, rel=1e-3)
    plain = RhythmicBlackBoxWrapper(gym.make("Swimmer-v5"))                 # the wrapper looks the env up too
    assert np.array_equal(plain.theta0, swimmer.theta0)
    swimmer.reset(seed=0)
    # the return of a = 0 as published (results/blackbox_defaults.json: 347-353 on seeds 0-4); a change of the
    # defaults moves it far more
    assert swimmer.step(np.zeros(swimmer.action_space.shape, np.float32))[1] == pytest.approx(347.082, rel=1e-3)
    swimmer.close()
    plain.close()


def test_derived_defaults_follow_the_rules(hopper, pendulum):
    derived = hopper.model_defaults
    model = hopper.env.unwrapped.model
    assert derived.controller == "pd" and derived.passive == () and hopper.controller.name == "pd"
    np.testing.assert_array_equal(derived.posture, hopper.env.unwrapped.init_qpos[hopper._read.qpos_adr])
    np.testing.assert_allclose(derived.joint_range, np.ptp(model.jnt_range[hopper._read.joint_ids], axis=1))
    np.testing.assert_allclose(derived.amplitude, MODEL_RULES["amplitude"] * derived.joint_range)
    stiffness = derived.p_gains * derived.force_per_command
    full_command = derived.force_per_command * 1.0 / (MODEL_RULES["full_command_error"] * derived.joint_range)
    cap = derived.inertia * (MODEL_RULES["stability"] / hopper.dt) ** 2
    np.testing.assert_allclose(stiffness, np.minimum(full_command, cap))
    np.testing.assert_allclose((derived.d_gains * derived.force_per_command) ** 2, 4 * stiffness * derived.inertia)
    assert np.all(derived.inertia > 0) and 0.5 < derived.period < 5.0
    # the inverted pendulum's pole is a passive joint: the pattern holds the posture, slowly
    held = pendulum.model_defaults
    assert held.passive == ("hinge",)
    np.testing.assert_allclose(held.amplitude, MODEL_RULES["hold_amplitude"] * held.joint_range)
    natural = 2 * np.pi * np.sqrt(held.length / 9.81)
    assert held.period == pytest.approx(MODEL_RULES["hold_periods"] * natural)


def test_reacher_unlimited_joint_and_critical_damping_for_given_gains():
    reacher = make_blackbox("Reacher-v5")
    derived = reacher.model_defaults
    assert reacher.n_joints == 2 and reacher.n_steps == 50 and derived.joint_range[0] == pytest.approx(2 * np.pi)
    given = make_blackbox("Reacher-v5", p_gains=2.0)
    np.testing.assert_allclose(given.controller.d_gains, derived.critical_damping(np.full(2, 2.0)))
    reacher.reset(seed=0)
    _, _, _, _, info = reacher.step(np.zeros(reacher.action_space.shape, np.float32))
    assert info["env_steps"] == 50 and info["tracking_rmse"] < 0.05 and info["clipped_fraction"] < 0.05
    reacher.close()
    given.close()


def test_the_default_pattern_lasts_as_long_as_the_zero_action(pendulum, hopper):
    for seed in range(5):
        assert pattern_steps(pendulum, seed) >= zero_action_steps("InvertedPendulum-v5", seed), seed
    for seed in range(2):
        assert pattern_steps(hopper, seed) >= zero_action_steps("Hopper-v5", seed), seed


def test_no_option_is_needed_on_a_mujoco_env_and_the_messages_say_what_to_pass():
    assert env_defaults("Hopper-v5") == {}                 # nothing hand-set: all from the model
    with pytest.raises(ValueError, match=r"p_gains: .* pass p_gains="):
        RhythmicBlackBoxWrapper(LooseJoints(), joint_state=read_joints, dt=DT, duration=1.0)


SERVOS = """<mujoco><compiler angle="radian"/><option timestep="0.002"/><worldbody><body>
<joint name="a" type="hinge" range="-1 1"/><geom size="0.05" fromto="0 0 0 0.3 0 0" type="capsule"/>
<body pos="0.3 0 0"><joint name="b" type="hinge"/>
<geom size="0.04" fromto="0 0 0 0.3 0 0" type="capsule"/></body></body></worldbody><actuator>{}</actuator></mujoco>"""


class Servos(gym.Env):
    """A two-link arm of the given actuators, 10 ms per step (no Gymnasium MuJoCo base class)."""

    metadata = {"render_modes": []}  # noqa: RUF012 (gymnasium's class attribute)

    def __init__(self, actuators: str) -> None:
        self.model = mujoco.MjModel.from_xml_string(SERVOS.format(actuators))
        self.data = mujoco.MjData(self.model)
        self.init_qpos = np.array([0.2, 0.0])
        self.dt = 0.01
        self.action_space = gym.spaces.Box(-2.0, 2.0, (2,), np.float32)
        self.observation_space = gym.spaces.Box(-np.inf, np.inf, (4,), np.float64)

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        mujoco.mj_resetData(self.model, self.data)
        self.data.qpos[:] = self.init_qpos
        mujoco.mj_forward(self.model, self.data)
        return np.r_[self.data.qpos, self.data.qvel], {}

    def step(self, action):
        self.data.ctrl[:] = action
        mujoco.mj_step(self.model, self.data, nstep=5)
        return np.r_[self.data.qpos, self.data.qvel], 0.0, False, False, {}


def test_the_controller_follows_the_actuators():
    position = RhythmicBlackBoxWrapper(Servos('<position joint="a" kp="50"/><position joint="b" kp="50"/>'),
                                       duration=1.0)
    assert position.controller.name == "position" and position.model_defaults.p_gains is None
    assert position.posture.tolist() == [0.2, 0.0] and position.model_defaults.passive == ()
    velocity = RhythmicBlackBoxWrapper(Servos('<velocity joint="a" kv="5"/><velocity joint="b" kv="5"/>'),
                                       duration=1.0)
    assert velocity.controller.name == "velocity"
    motors = RhythmicBlackBoxWrapper(Servos('<motor joint="a" gear="3"/><motor joint="b" gear="3"/>'), duration=1.0)
    assert motors.controller.name == "pd" and np.all(motors.controller.p_gains > 0)
    assert motors.model_defaults.joint_range[1] == pytest.approx(2 * np.pi)     # b has no limits
    with pytest.raises(ValueError, match="controller: the actuators are not all motors"):
        RhythmicBlackBoxWrapper(Servos('<motor joint="a"/><position joint="b" kp="50"/>'), duration=1.0)
    with pytest.raises(ValueError, match="controller: the position servos have a gear other than 1"):
        RhythmicBlackBoxWrapper(Servos('<position joint="a" kp="50" gear="2"/><position joint="b" kp="50"/>'),
                                duration=1.0)
    mixed = RhythmicBlackBoxWrapper(Servos('<motor joint="a"/><position joint="b" kp="50"/>'), duration=1.0,
                                    controller=lambda q_des, qd_des, q, qd: q_des - q)
    assert mixed.n_joints == 2


# ------------------------------------------------------------------ the task contract
def test_task_contract_and_executed_path(pendulum):
    contract = contract_of(pendulum)
    assert contract.name == "InvertedPendulum-v5" and contract.metric_keys == ("env_steps", "tracking_rmse")
    assert contract.metric("tracking_rmse").higher_is_better is False and contract.metric("env_steps").unit == "steps"
    assert not contract.has_success and contract.smoothness == "jerk" and contract.dt == pendulum.dt
    assert contract.path_labels == ("slider",)
    action = np.random.default_rng(0).uniform(-1, 1, pendulum.action_space.shape).astype(np.float32)
    pendulum.reset(seed=3)
    path = pendulum.executed_path(action)
    assert path.shape == (pendulum.n_steps, 1)
    _, _, _, _, info = pendulum.step(action)
    np.testing.assert_array_equal(path, info["desired_positions"][1:])
    values = metric_values(contract, info)
    assert values == {"env_steps": float(info["env_steps"]), "tracking_rmse": info["tracking_rmse"]}
    assert isinstance(info["env_steps"], int) and isinstance(info["tracking_rmse"], float)


# ------------------------------------------------------------------ video
def test_record_episode_writes_a_video(tmp_path, pendulum):
    assert not pendulum.can_record()
    pendulum.reset(seed=0)
    with pytest.raises(ValueError, match="render_mode: recording needs the env made with render_mode='rgb_array'"):
        pendulum.record_episode(np.zeros(pendulum.action_space.shape, np.float32), tmp_path / "no.gif")
    env = make_blackbox("InvertedPendulum-v5", render_mode="rgb_array", env_kwargs={"width": 64, "height": 64},
                        duration=0.4)
    assert env.can_record()
    env.reset(seed=0)
    env.step(np.zeros(env.action_space.shape, np.float32))
    with pytest.raises(RuntimeError, match="reset"):                     # every episode needs its reset
        env.record_episode(np.zeros(env.action_space.shape, np.float32), tmp_path / "late.mp4")
    env.reset(seed=0)
    _, _, terminated, _, info = env.record_episode(np.zeros(env.action_space.shape, np.float32),
                                                   tmp_path / "episode.mp4")
    assert terminated and info["env_steps"] == 10 and (tmp_path / "episode.mp4").stat().st_size > 0
    import imageio.v2 as imageio

    with imageio.get_reader(tmp_path / "episode.mp4") as reader:
        assert reader.count_frames() == 11                               # the reset state and every env step
        assert reader.get_data(0).shape == (64, 64, 3)
    env.close()
