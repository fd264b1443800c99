"""The rhythmic black-box wrapper (rdmp_gym.envs.blackbox) on a tiny numpy env with joints, and on Swimmer-v5."""

from __future__ import annotations

import json

import gymnasium as gym
import numpy as np
import pytest
from rdmp_gym.agents.learners import EpisodeBatch, make_learner
from rdmp_gym.agents.learners.contextual import action_layout
from rdmp_gym.agents.tasks import run_episode
from rdmp_gym.envs.blackbox import (
    BLACKBOX_ID,
    RhythmicBlackBoxWrapper,
    default_demonstration,
    env_defaults,
    make_blackbox,
)

from rdmp_gym import Demonstration, RhythmicDMP

DT = 0.01


class TwoJoints(gym.Env):
    """Two joints with unit inertia and light damping, integrated at 1 kHz, ``DT`` s per step; no MuJoCo.

    ``mode``: ``"torque"`` (action = joint torques, box ±``limit``), ``"position"`` or ``"velocity"`` (action = a
    joint target that a stiff servo inside the env follows). The observation is ``[q, qd, centre]``; the reward per
    step is ``-DT * |q - centre|²`` (stay near the centre); ``terminate_at``: the episode ends after that many steps.
    """

    metadata = {"render_modes": []}  # noqa: RUF012 (gymnasium's class attribute)

    def __init__(self, mode: str = "torque", limit: float = 50.0, terminate_at: int | None = None,
                 centre: tuple[float, float] = (0.1, -0.1)) -> None:
        self.mode, self.terminate_at = mode, terminate_at
        self.dt = DT
        high = limit if mode == "torque" else 3.0
        self.action_space = gym.spaces.Box(-high, high, (2,), np.float32)
        self.observation_space = gym.spaces.Box(-np.inf, np.inf, (6,), np.float64)
        self.centre = np.asarray(centre, dtype=np.float64)
        self.q, self.qd, self.steps = np.zeros(2), np.zeros(2), 0

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.q = self.np_random.uniform(-0.05, 0.05, 2)
        self.qd = self.np_random.uniform(-0.1, 0.1, 2)
        self.steps = 0
        return self._obs(), {}

    def _obs(self):
        return np.r_[self.q, self.qd, self.centre]

    def step(self, action):
        action = np.asarray(action, dtype=np.float64)
        h = DT / 10
        for _ in range(10):
            if self.mode == "torque":
                acc = action - 0.1 * self.qd
            elif self.mode == "position":
                acc = 40000.0 * (action - self.q) - 400.0 * self.qd
            else:
                acc = 200.0 * (action - self.qd)
            self.qd = self.qd + h * acc
            self.q = self.q + h * self.qd
        self.steps += 1
        reward = -DT * float(np.sum((self.q - self.centre) ** 2))
        terminated = self.terminate_at is not None and self.steps >= self.terminate_at
        return self._obs(), reward, terminated, False, {}


def read_joints(env):
    base = env.unwrapped
    return base.q.copy(), base.qd.copy()


def wrap(mode="torque", **settings):
    env = TwoJoints(mode, terminate_at=settings.pop("terminate_at", None))
    gains = {"torque": {"p_gains": 2500.0, "d_gains": 100.0}, "position": {}, "velocity": {"p_gains": 20.0}}[mode]
    defaults = {"joint_state": read_joints, "controller": "pd" if mode == "torque" else mode, "duration": 3.0,
                "period": 1.0, "amplitude": 0.2, "posture": (0.0, 0.0), **gains}
    return RhythmicBlackBoxWrapper(env, **{**defaults, **settings})


@pytest.fixture(scope="module")
def arm():
    return wrap()


def episode(env, action, seed=0):
    context, _ = env.reset(seed=seed)
    return (context, *env.step(np.asarray(action, dtype=np.float32)))


# ------------------------------------------------------------------ tracking and the initial DMP
@pytest.mark.parametrize(("mode", "bound"), [("torque", 0.05), ("position", 0.03), ("velocity", 0.05)])
def test_executed_trajectory_follows_the_desired_one(mode, bound):
    env = wrap(mode)
    rng = np.random.default_rng(1)
    for action in (np.zeros(env.action_space.shape), rng.uniform(-0.5, 0.5, env.action_space.shape)):
        _, _, _, _, _, info = episode(env, action, seed=3)
        motion = np.ptp(info["desired_positions"], axis=0)
        assert info["env_steps"] == env.n_steps == 300
        assert info["positions"].shape == info["desired_positions"].shape == (301, 2)
        assert np.array_equal(info["positions"][0], info["desired_positions"][0])   # starts where the env was reset
        assert np.all(np.abs(info["tracking_error"]).max(axis=0) < bound * motion), (mode, info["tracking_rmse"])
        assert info["clipped_fraction"] == 0.0


def test_action_zero_executes_the_initial_dmp(arm):
    _, _, _, _, _, info = episode(arm, np.zeros(arm.action_space.shape), seed=5)
    assert np.array_equal(info["params"], arm.theta0)
    assert np.array_equal(arm.action_to_params(np.zeros(arm.action_space.shape)), arm.theta0)
    q0, qd0 = info["positions"][0], info["velocities"][0]
    y, yd = arm.dmp.rollout(arm.t, 0, y0=q0, yd0=qd0, return_velocity=True)
    np.testing.assert_allclose(info["desired_positions"], y, rtol=0, atol=1e-12)
    np.testing.assert_allclose(info["desired_velocities"], yd, rtol=0, atol=1e-12)
    batch = arm.dmp.rollout_batch(arm.theta0[None], arm.t, arm.groups, y0=q0, yd0=qd0)[0]
    np.testing.assert_allclose(info["desired_positions"], batch, rtol=0, atol=1e-9)
    # the default pattern: a sine of 0.2 about the posture once the start is over, joint 1 a quarter period behind
    late = arm.t >= 1.5
    np.testing.assert_allclose(np.ptp(y[late], axis=0), 0.4, rtol=0.05)
    demo, _ = default_demonstration(np.zeros(2), 1.0, 0.2)
    expected = np.array([np.interp(arm.t[late], demo.t, column) for column in demo.Y.T]).T
    assert np.abs(y[late] - expected).max() < 0.01


def test_velocities_are_the_derivative_of_the_positions(arm):
    _, _, _, _, _, info = episode(arm, np.full(arm.action_space.shape, 0.3), seed=2)
    y, yd = info["desired_positions"], info["desired_velocities"]
    np.testing.assert_allclose(np.gradient(y, arm.t, axis=0)[2:-2], yd[2:-2], atol=0.01 * np.abs(yd).max())


def test_same_seed_same_numbers():
    first, second = wrap(), wrap()
    action = np.random.default_rng(0).uniform(-1, 1, first.action_space.shape)
    a = episode(first, action, seed=11)
    b = episode(second, action, seed=11)
    c = episode(first, action, seed=12)
    assert a[2] == b[2] and np.array_equal(a[0], b[0])
    for key in ("positions", "desired_positions", "step_rewards", "cost_trace", "env_actions"):
        assert np.array_equal(a[-1][key], b[-1][key]), key
    assert a[2] != c[2]


# ------------------------------------------------------------------ the episodic contract
def test_episodic_api_and_cost_trace(arm):
    shape = arm.action_space.shape
    assert arm.action_space.dtype == np.float32 and arm.observation_space.dtype == np.float32
    assert arm.unwrapped is arm
    action = np.random.default_rng(3).uniform(-1, 1, shape).astype(np.float32)
    np.testing.assert_allclose(arm.params_to_action(arm.action_to_params(action)), action, atol=1e-6)
    weights = arm.action_time_weights()
    assert weights.shape == (arm.n_steps, shape[0]) and weights.min() >= 0.0 and weights.max() <= 1.0
    periodic = arm.param_map.slices["periodic"]
    assert np.all(weights[:, periodic].max(axis=0) > 0.2)        # every periodic weight acts somewhere
    arm.reset(seed=0)
    context, reward, terminated, truncated, info = arm.step(action)
    assert terminated and not truncated and context.dtype == np.float32
    assert info["cost_trace"].shape == (arm.n_steps,)
    assert info["cost_trace"].sum() == pytest.approx(-reward, abs=1e-12)
    assert reward == pytest.approx(float(np.sum(info["step_rewards"])), abs=1e-12)
    assert action_layout(arm)[0] == arm.dmp.param_slices(arm.groups)
    metrics = run_episode(arm, action, seed=0, options=None)            # the learners' own episode runner
    assert metrics["return"] == pytest.approx(reward) and metrics["cost_trace"].shape == (arm.n_steps,)


def test_step_needs_a_reset_each_episode(arm):
    arm.reset(seed=0)
    arm.step(np.zeros(arm.action_space.shape))
    with pytest.raises(RuntimeError, match="reset"):
        arm.step(np.zeros(arm.action_space.shape))


def test_early_termination_is_reported_and_padded():
    env = wrap(terminate_at=40)
    _, _, reward, terminated, _, info = episode(env, np.zeros(env.action_space.shape))
    assert terminated and info["env_terminated"] and info["terminated_early"] and not info["env_truncated"]
    assert info["env_steps"] == 40 and info["step_rewards"].shape == (40,) and info["positions"].shape == (41, 2)
    assert info["cost_trace"].shape == (env.n_steps,) and np.all(info["cost_trace"][40:] == 0.0)
    assert info["cost_trace"].sum() == pytest.approx(-reward)
    assert info["desired_positions"].shape == (env.n_steps + 1, 2)


def test_context_mask_selects_the_reset_observation():
    env = wrap(context_mask=[False, False, False, False, True, True])
    context, _ = env.reset(seed=0)
    assert env.observation_space.shape == (2,) and np.array_equal(context, np.float32([0.1, -0.1]))
    assert env.observation_space.contains(context)
    final, *_ = env.step(np.zeros(env.action_space.shape))
    assert np.array_equal(final, context)
    full = wrap()
    observation, _ = full.reset(seed=4)
    assert observation.shape == (6,) and np.array_equal(observation, np.float32(full.env._obs()))


# ------------------------------------------------------------------ clear errors
class Discrete(TwoJoints):
    def __init__(self):
        super().__init__()
        self.action_space = gym.spaces.Discrete(3)


def test_refuses_what_it_cannot_drive():
    with pytest.raises(ValueError, match="continuous Box action space"):
        RhythmicBlackBoxWrapper(Discrete(), joint_state=read_joints, duration=1.0, p_gains=1.0)
    with pytest.raises(ValueError, match="joint_state: the env has no MuJoCo"):
        RhythmicBlackBoxWrapper(TwoJoints(), duration=1.0, p_gains=1.0)
    with pytest.raises(ValueError, match="context_mask: expected 6 booleans"):
        wrap(context_mask=[True, False])
    with pytest.raises(ValueError, match="context_mask"):
        wrap(context_mask=[0, 1, 2, 3, 4, 5])
    with pytest.raises(ValueError, match="p_gains"):
        wrap(p_gains=None)
    with pytest.raises(ValueError, match="p_gains"):
        wrap(p_gains=-1.0)
    with pytest.raises(ValueError, match="controller"):
        wrap(controller="torque")
    with pytest.raises(ValueError, match="duration"):
        wrap(duration=0.005)
    with pytest.raises(ValueError, match="dt: the env has no"):
        env = TwoJoints()
        del env.dt
        RhythmicBlackBoxWrapper(env, joint_state=read_joints, duration=1.0, p_gains=1.0)
    with pytest.raises(ValueError, match="duration: the env has no time limit"):
        RhythmicBlackBoxWrapper(TwoJoints(), joint_state=read_joints, p_gains=1.0)
    with pytest.raises(ValueError, match="demonstration: has 3 dimensions"):
        demo, _ = default_demonstration(np.zeros(3), 1.0, 0.2)
        wrap(demonstration=demo)
    with pytest.raises(ValueError, match="groups"):
        wrap(groups=("periodic", "bogus"))


def test_refuses_bad_actions(arm):
    arm.reset(seed=0)
    bad = np.zeros(arm.action_space.shape)
    bad[3] = np.nan
    with pytest.raises(ValueError, match="action: contains NaN"):
        arm.step(bad)
    with pytest.raises(ValueError, match="action: expected shape"):
        arm.step(np.zeros(arm.action_space.shape[0] + 1))
    with pytest.raises(ValueError, match="action: contains NaN"):
        arm.action_to_params(bad)
    arm.step(np.zeros(arm.action_space.shape))          # a refused action does not use up the episode


def test_joint_state_reader_output_is_checked():
    env = wrap(joint_state=lambda env: (np.zeros(3), np.zeros(3)))
    with pytest.raises(ValueError, match="joint_state: expected"):
        env.reset(seed=0)


# ------------------------------------------------------------------ demonstrations and groups
def test_fits_a_demonstration_and_selected_groups():
    t = np.arange(0, 5.0, 0.01)
    u = np.clip(t / 0.8, 0, 1)
    Y = np.c_[0.3 * u**2 * np.sin(2 * np.pi * t / 0.8), 0.1 + 0.2 * u**2 * np.cos(2 * np.pi * t / 0.8)]
    env = wrap(demonstration=Demonstration(t, Y), groups=("periodic", "transient", "initial"), n_periodic=8,
               n_transient=6)
    assert env.dmp.period == pytest.approx(0.8, rel=0.02)
    assert env.action_space.shape == (2 * 8 + 2 * 6 + 2,)
    _, _, _, _, _, info = episode(env, np.zeros(env.action_space.shape))
    late = env.t > 2.0
    np.testing.assert_allclose(np.ptp(info["desired_positions"][late], axis=0), [0.6, 0.4], rtol=0.1)
    fitted = RhythmicDMP.fit(Demonstration(t, Y), 8, 6)
    assert wrap(dmp=fitted).dmp is fitted


# ------------------------------------------------------------------ a learner through the agents' ask/tell
def test_a_learner_improves_on_the_tiny_env():
    """CMA-ES from rdmp_gym.agents.learners with the env's episodes (no training loop): the task rewards staying
    near (0.1, -0.1), so shifting the anchor and shrinking the amplitude pays; 8 updates of 8 episodes."""
    env = wrap(duration=2.0, groups=("amplitude", "anchor"))
    learner = make_learner("cmaes", np.zeros(env.action_space.shape[0]), 8, np.random.default_rng(0),
                           {"sigma": 0.4})
    start = run_episode(env, learner.mean, 0, None)["return"]
    for update in range(8):
        actions = learner.ask()
        results = [run_episode(env, action, seed, None) for seed, action in enumerate(actions)]
        learner.tell(EpisodeBatch(actions=actions, returns=np.array([r["return"] for r in results]),
                                  cost_traces=np.stack([r["cost_trace"] for r in results]),
                                  valid=np.ones(8, bool), seeds=np.arange(8) + 8 * update))
    end = run_episode(env, learner.mean, 0, None)["return"]
    assert end > 0.5 * start          # returns are negative: the cost has at least halved


def test_pi2_takes_the_time_weights(arm):
    learner = make_learner("pi2", np.zeros(arm.action_space.shape[0]), 4, np.random.default_rng(0), {},
                           time_weights=arm.action_time_weights())
    actions = learner.ask()
    results = [run_episode(arm, action, seed, None) for seed, action in enumerate(actions)]
    learner.tell(EpisodeBatch(actions=actions, returns=np.array([r["return"] for r in results]),
                              cost_traces=np.stack([r["cost_trace"] for r in results]),
                              valid=np.ones(4, bool), seeds=np.arange(4)))
    assert learner.updates == 1 and np.all(np.isfinite(learner.mean))


# ------------------------------------------------------------------ a Gymnasium MuJoCo env
def test_swimmer_one_short_episode():
    env = make_blackbox("Swimmer-v5", duration=2.0, amplitude=0.5)    # within the motors' torque: the PD follows it
    assert env.n_joints == 2 and env.dt == pytest.approx(0.04) and env.n_steps == 50
    assert env.controller.name == "pd" and env_defaults("Swimmer-v5")["p_gains"] == 10.0
    context, _ = env.reset(seed=0)
    assert context.shape == (8,) and context.dtype == np.float32
    reset_joints = env.env.unwrapped.data.qpos[[3, 4]].copy()       # Swimmer's two hinges (after the root's 3)
    _, reward, terminated, _, info = env.step(np.zeros(env.action_space.shape))
    assert terminated and np.isfinite(reward) and info["env_steps"] == 50
    assert info["tracking_rmse"] < 0.1 and info["positions"].shape == (51, 2)
    np.testing.assert_array_equal(info["positions"][0], reset_joints)
    np.testing.assert_array_equal(info["positions"][-1], env.env.unwrapped.data.qpos[[3, 4]])
    again = gym.make(BLACKBOX_ID, env_id="Swimmer-v5", duration=2.0, amplitude=0.5, disable_env_checker=True)
    again.reset(seed=0)
    _, same, *_ = again.step(np.zeros(env.action_space.shape, np.float32))
    assert same == reward
    with pytest.raises(ValueError, match="duration: 50 s is 1250 env steps, more than the env's time limit"):
        make_blackbox("Swimmer-v5", duration=50.0)
    with pytest.raises(ValueError, match="posture: expected 2 joint positions"):
        make_blackbox("Swimmer-v5", duration=2.0, posture=(0.0, 0.0, 0.0))
    env.close()
    again.close()


def test_the_agents_wrap_a_step_based_env_and_refuse_one_the_wrapper_cannot_drive():
    from rdmp_gym.agents.tasks import TaskSpec

    env = TaskSpec("Swimmer-v5").make()
    assert all(hasattr(env.unwrapped, name) for name in ("action_to_params", "params_to_action",
                                                         "action_time_weights"))
    env.reset(seed=0)
    _, _, terminated, _, info = env.step(np.zeros(env.action_space.shape, np.float32))
    assert terminated and info["env_steps"] > 0 and np.isfinite(info["cost_trace"]).all()
    env.close()
    with pytest.raises(ValueError, match="continuous Box action space"):
        TaskSpec("CartPole-v1").make()


# ------------------------------------------------------------------ HalfCheetah, tempo, settings through the agents
def test_halfcheetah_defaults_build_and_track():
    env = make_blackbox("HalfCheetah-v5", duration=1.0)
    defaults = env_defaults("HalfCheetah-v5")
    assert defaults["controller"] == "pd" and defaults["p_gains"] > 0 and defaults["period"] == pytest.approx(1 / 3.81)
    assert env.n_joints == 6 and env.n_steps == 20 and env.controller.name == "pd"
    env.reset(seed=0)
    _, reward, terminated, _, info = env.step(np.zeros(env.action_space.shape, np.float32))
    assert terminated and np.isfinite(reward) and info["env_steps"] == 20
    desired = info["desired_positions"]
    assert np.ptp(desired[1:], axis=0).min() > 0.05                  # every joint moves in the pattern ...
    assert info["tracking_rmse"] < 0.35 and info["clipped_fraction"] < 0.05     # ... and the PD follows it
    env.close()


def test_tempo_is_one_action_dimension_and_a_plus_runs_the_cycle_faster():
    env = make_blackbox("Swimmer-v5", groups=("periodic", "tempo"), duration=20.0)
    plain = make_blackbox("Swimmer-v5", groups=("periodic",), duration=20.0)
    assert env.action_space.shape[0] == plain.action_space.shape[0] + 1
    assert list(env.action_slices()) == ["periodic", "tempo"]
    assert env.action_time_weights().shape == (env.n_steps, env.action_space.shape[0])
    env.reset(seed=0)
    zero = np.zeros(env.action_space.shape, np.float32)
    faster = zero.copy()
    faster[-1] = 0.6                                                # tempo 1 + 0.5 * 0.6 = 1.3
    np.testing.assert_array_equal(env.desired_trajectory(env.action_to_params(zero))[0],
                                  plain.desired_trajectory(plain.theta0, *env._start)[0])

    def period(path):
        x = path[len(path) // 3:, 0] - path[len(path) // 3:, 0].mean()
        ups = np.flatnonzero(np.diff(np.sign(x)) > 0)
        return float(np.mean(np.diff(ups))) * env.dt

    base, quick = (period(env.desired_trajectory(env.action_to_params(a))[0]) for a in (zero, faster))
    assert base == pytest.approx(env.dmp.period, rel=0.05) and quick == pytest.approx(base / 1.3, rel=0.05)
    assert env.policy_dmp(env.action_to_params(faster)).canonical.tempo == pytest.approx(1.3)
    with pytest.raises(ValueError, match="scales: tempo must be < 1"):
        make_blackbox("Swimmer-v5", groups=("periodic", "tempo"), scales={"tempo": 1.0})
    env.close()
    plain.close()


def test_env_options_reach_the_wrapper_and_an_unknown_one_is_named(tmp_path, capsys):
    from rdmp_gym.agents.cli import main
    from rdmp_gym.agents.run_commands import parse_train, train_config
    from rdmp_gym.agents.tasks import TaskSpec
    from rdmp_gym.agents.training import TrainConfig

    env = TaskSpec("Swimmer-v5", {"p_gains": 4.0, "duration": 2.0, "ctrl_cost_weight": 0.0}).make()
    base = env.unwrapped
    assert isinstance(base, RhythmicBlackBoxWrapper) and base.n_steps == 50
    np.testing.assert_array_equal(base.controller.p_gains, [4.0, 4.0])
    assert base.controller.d_gains[0] == 0.5 and base.env.unwrapped._ctrl_cost_weight == 0.0   # default; env keyword
    env.close()
    with pytest.raises(ValueError, match="'p_gain' is neither a setting of the rhythmic black-box wrapper"):
        TrainConfig(agent="cmaes", env_id="Swimmer-v5", env_kwargs={"p_gain": 4.0})
    command = parse_train(["--agent", "cmaes", "--env", "Swimmer-v5", "--out", str(tmp_path / "run"), "--env-option",
                           "duration", "0.4", "--env-option", "groups", '["amplitude", "tempo"]', "--env-option",
                           "p_gains", "4"])
    config = train_config(command)
    assert config.env_kwargs == {"duration": 0.4, "groups": ["amplitude", "tempo"], "p_gains": 4}
    again = TrainConfig.from_dict(json.loads(json.dumps(config.to_dict()))).task.make().unwrapped
    assert again.action_space.shape == (3,) and again.n_steps == 10 and again.controller.p_gains[0] == 4.0
    again.close()
    capsys.readouterr()
    assert main(["train", "--agent", "cmaes", "--env", "Swimmer-v5", "--out", str(tmp_path / "bad"),
                 "--env-option", "p_gain", "3"]) == 2
    assert "p_gain" in capsys.readouterr().err


def test_the_shrunk_start_scales_the_pattern_and_keeps_the_tempo():
    from types import SimpleNamespace

    from rdmp_gym.agents.training import TrainConfig, _initial_action

    env = wrap(groups=("periodic", "amplitude", "tempo"))
    config = TrainConfig(agent="cmaes", env_id="Swimmer-v5", start="shrunk", perturbation=0.2)
    evaluator = SimpleNamespace(env=env, n_actions=env.action_space.shape[0])
    action = _initial_action(config, evaluator, np.random.default_rng(0))
    slices = env.param_slices()
    theta0, theta = env.action_to_params(np.zeros_like(action)), env.action_to_params(action)
    for name in ("periodic", "amplitude"):
        np.testing.assert_allclose(theta[slices[name]], 0.8 * theta0[slices[name]], rtol=1e-6, atol=1e-9)
    assert theta[slices["tempo"]] == pytest.approx(theta0[slices["tempo"]]) and action[slices["tempo"]] == 0.0
