"""Contextual learners, smooth exploration, smooth bounds and the protocol's statistics (MuJoCo-free)."""

import os
from types import SimpleNamespace

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np
import pytest
from rdmp_gym.agents.learners import EpisodeBatch, SearchSpace, make_learner
from rdmp_gym.agents.learners.contextual import policy_from_state
from rdmp_gym.agents.learners.smooth_exploration import SmoothNoise, block_layout, squash, unsquash
from rdmp_gym.agents.protocol import defined_interval, final_test_seeds, interval, iqm, success, validation_seeds
from rdmp_gym.agents.training import TRAIN_SEED_LIMIT, TrainConfig, train
from rdmp_gym.envs.contract import TaskContract
from rdmp_gym.envs.registration import TRACKING_ID

N = 12


def _space(contexts=2):
    return SearchSpace({"periodic": slice(0, N - 2), "amplitude": slice(N - 2, N)}, 2, np.zeros(contexts),
                       np.ones(contexts))


def _batch(actions, returns):
    k = len(returns)
    return EpisodeBatch(actions, np.asarray(returns, dtype=float), np.zeros((k, 1)), np.ones(k, dtype=bool),
                        np.zeros(k, dtype=np.int64))


def _toy(agent, target, updates=60, seed=0, **options):
    """Learn ``max -|a - target(s)|²`` over contexts ``s ~ U[-1, 1]²``; policy score on 50 held-out contexts."""
    rng = np.random.default_rng(100 + seed)
    learner = make_learner(agent, np.zeros(N), 10, np.random.default_rng(seed), options, space=_space())
    held_out = rng.uniform(-1, 1, (50, 2))

    def score():
        return -np.mean(np.sum((learner.policy_actions(held_out) - target(held_out)) ** 2, axis=1))

    history, asked = [score()], []
    for _ in range(updates):
        contexts = rng.uniform(-1, 1, (10, 2))
        actions = learner.ask(contexts)
        asked.append(actions)
        learner.tell(_batch(actions, -np.sum((actions - target(contexts)) ** 2, axis=1)))
        history.append(score())
    return np.array(history), np.concatenate(asked), learner


GAINS = np.random.default_rng(5).uniform(-0.5, 0.5, (N, 2))


def _contextual_target(contexts):
    return 0.2 + contexts @ GAINS.T


def test_smooth_exploration_has_far_smaller_second_differences_than_isotropic():
    blocks = block_layout({"periodic": slice(0, 120), "transient:0": slice(120, 240), "amplitude": slice(240, 243)}, 3)
    assert len(blocks) == 7 and blocks[0] == (slice(0, 40), True) and blocks[3] == (slice(120, 160), False)
    rng = np.random.default_rng(0)
    smooth = SmoothNoise(243, blocks, 5.0).sample(np.full(7, 0.3), 400, rng)
    white = SmoothNoise(243, blocks, 0.0).sample(np.full(7, 0.3), 400, rng)
    np.testing.assert_allclose(np.std(smooth[:, :240]), 0.3, rtol=0.1)        # same size per weight ...
    np.testing.assert_allclose(np.std(white[:, :240]), 0.3, rtol=0.1)
    rough = [np.mean(np.diff(x[:, 120:160], 2, axis=1) ** 2) for x in (smooth, white)]
    assert rough[0] < 0.02 * rough[1]                                          # ... far smoother
    cost = SmoothNoise(243, blocks, 5.0)
    assert np.mean(cost.control_cost(smooth)) < 0.02 * np.mean(cost.control_cost(white))


def test_bounded_samples_stay_in_the_box_and_the_update_finds_an_optimum_near_a_face():
    assert np.all(np.abs(squash(np.linspace(-50, 50, 1001))) <= 1.0)
    u = np.linspace(-2.5, 2.5, 1001)
    a = squash(u)
    assert np.all(np.abs(a) < 1.0) and np.all(np.diff(a) > 0)               # monotone into the open box
    np.testing.assert_allclose(squash(np.array([-0.3, 0.5, 0.8])), [-0.3, 0.5, 0.8])   # identity inside
    np.testing.assert_allclose(unsquash(a), u, atol=1e-9)
    history, asked, learner = _toy("amplitude", lambda s: np.full((len(s), N), 0.7), updates=50, groups=[],
                                   sigma=0.6)                           # REPS with one θ for all contexts
    assert np.all(np.abs(asked) <= 1.0)
    assert np.max(np.abs(learner.mean - 0.7)) < 0.05                          # no pull toward 0 or toward the face
    assert history[-1] > -0.01


def test_contextual_reps_solves_a_contextual_quadratic_far_better_than_a_shared_theta():
    contextual, _, _ = _toy("creps", _contextual_target, length=0.0, gain_prior=0.01)
    shared, _, _ = _toy("amplitude", _contextual_target, gain_prior=0.01, groups=[])    # REPS, one θ
    best_shared = -np.sum(GAINS**2) / 3                                        # the best single θ's expected loss
    assert contextual[-1] > 0.3 * best_shared                                  # < 30 % of the best shared loss
    assert shared[-1] < 0.7 * best_shared
    baseline, _, _ = _toy("cpibb", _contextual_target, length=0.0, gain_prior=0.01)
    assert baseline[-1] > 0.3 * best_shared


def test_random_return_control_does_not_improve():
    control = np.array([_toy("random", _contextual_target, updates=30, seed=s)[0] for s in range(3)])
    learned = np.array([_toy("creps", _contextual_target, updates=30, seed=s)[0] for s in range(3)])
    assert np.all(control[:, -1] <= control[:, 0] + 0.02)
    assert np.all(learned[:, -1] > learned[:, 0] + 0.3)


def test_state_round_trip_continues_identically():
    _, _, learner = _toy("cpibb", _contextual_target, updates=3)
    state = learner.state_dict()
    twin = make_learner("cpibb", np.zeros(N), 10, np.random.default_rng(99), None, space=_space())
    twin.load_state_dict(state)
    contexts = np.random.default_rng(7).uniform(-1, 1, (10, 2))
    np.testing.assert_array_equal(twin.ask(contexts), learner.ask(contexts))
    for value in state.values():   # plain numbers, arrays, dicts of arrays (no objects)
        assert isinstance(value, (str, int, float, np.ndarray, dict))


class _Declared:
    """An env that declares only its context fields (its contract) and an action space of ``N``."""

    action_space = SimpleNamespace(shape=(N,))

    def __init__(self, fields):
        self.fields = fields

    @property
    def unwrapped(self):
        return self

    def task_contract(self):
        return TaskContract(name="fields", context_fields=self.fields)


def test_cup_position_features_are_gated_by_presence_and_standardised_over_cup_contexts():
    """ArmarWipe-v1's layout: [..., obstacle (0/1), obstacle x, y]; x, y are (0, 0) without a cup."""
    rng = np.random.default_rng(0)
    present = (rng.uniform(size=200) < 0.4).astype(float)
    position = np.where(present[:, None] > 0, rng.normal([-0.04, 0.13], [0.02, 0.01], (200, 2)), 0.0)
    obs = np.column_stack([rng.normal(0, 0.01, 200), present, position])
    env = _Declared({"obstacle": (1, 1), "obstacle_position": (2, 2)})
    space = SearchSpace.from_env(env, obs)
    assert space.context_gate.tolist() == [-1, -1, 1, 1]
    np.testing.assert_allclose(space.context_center[2:], position[present > 0].mean(axis=0))
    np.testing.assert_allclose(space.context_scale[2:], position[present > 0].std(axis=0))
    learner = make_learner("creps", np.zeros(N), 10, np.random.default_rng(0), space=space)
    phi = learner.features(obs)[:, 1:]
    assert np.all(phi[present == 0, 2:] == 0.0)                                   # no cup: no position feature
    np.testing.assert_allclose(phi[present > 0, 2:].std(axis=0), 1.0, rtol=1e-9)  # cup: unit scale
    learner.gains = rng.normal(size=learner.gains.shape)
    np.testing.assert_allclose(policy_from_state(learner.state_dict(), obs), learner.policy_actions(obs))
    assert SearchSpace.from_env(_Declared({}), obs).context_gate is None         # no fields: no gate


def test_a_state_without_a_context_policy_acts_with_its_mean_in_every_context():
    """CMA-ES has no context policy: the policy of its state is its mean, as the learner's own policy_actions."""
    from rdmp_gym.agents.learners import policy_from_state as any_policy_from_state

    learner = make_learner("cmaes", np.full(N, 0.1), 10, np.random.default_rng(0))
    learner.tell(EpisodeBatch(learner.ask(), -np.arange(10.0), np.zeros((10, 1)), np.ones(10, bool),
                              np.arange(10)))
    obs = np.random.default_rng(1).normal(size=(4, 3))
    np.testing.assert_allclose(any_policy_from_state(learner.state_dict(), obs), learner.policy_actions(obs))
    assert not np.allclose(learner.policy_actions(obs), 0.1)                     # the mean moved


def test_contextual_learner_rejects_bad_input():
    learner = make_learner("creps", np.zeros(N), 10, np.random.default_rng(0), space=_space())
    with pytest.raises(ValueError, match="observations"):
        learner.ask()
    with pytest.raises(ValueError, match="observations"):
        learner.ask(np.zeros((10, 3)))
    with pytest.raises(ValueError, match="groups"):
        make_learner("creps", np.zeros(N), 10, np.random.default_rng(0), {"groups": "transient"}, space=_space())
    with pytest.raises(ValueError, match="space"):
        make_learner("creps", np.zeros(N), 10, np.random.default_rng(0))
    with pytest.raises(ValueError, match=r"creps\.weighting: not an option of creps, which always runs with "
                                         r"weighting = 'reps'"):
        make_learner("creps", np.zeros(N), 10, np.random.default_rng(0), {"weighting": "pi2"}, space=_space())
    with pytest.raises(ValueError, match=r"sigma"):                  # above the exploration's ceiling
        make_learner("creps", np.zeros(N), 10, np.random.default_rng(0), {"sigma": 0.7}, space=_space())


def test_amplitude_baseline_moves_only_the_amplitude():
    _, asked, learner = _toy("amplitude", _contextual_target, updates=5)
    assert np.all(asked[:, : N - 2] == 0.0) and np.any(asked[:, N - 2:] != 0.0)
    assert learner.gains.shape == (N, 1)


def test_bootstrap_intervals_cover_the_true_value():
    rng = np.random.default_rng(0)
    samples = rng.standard_normal((100, 20)) + 3.0
    covered = [(found := interval(x, "mean", seed=i, resamples=1000)).low <= 3.0 <= found.high
               for i, x in enumerate(samples)]
    assert 0.85 <= np.mean(covered) <= 1.0
    covered_iqm = [(found := interval(x, "iqm", seed=i, resamples=1000)).low <= 3.0 <= found.high
                   for i, x in enumerate(samples)]
    assert 0.85 <= np.mean(covered_iqm) <= 1.0
    assert iqm(np.array([0.0, 1.0, 2.0, 3.0, 100.0, -100.0, 1.5, 2.5])) == pytest.approx(1.75)
    with pytest.raises(ValueError, match="values"):
        interval(np.array([1.0, np.nan]))
    assert defined_interval(np.array([1.0, np.nan, 3.0]), "mean") == interval(np.array([1.0, 3.0]), "mean").to_dict()
    assert defined_interval(np.array([np.nan, np.inf])) is None                  # no finite value: no interval


def test_protocol_context_sets_are_disjoint_and_success_is_the_envs_own():
    train, val, test = TRAIN_SEED_LIMIT, validation_seeds(50), final_test_seeds(50)
    assert test.min() >= train and val.min() >= train and not set(val) & set(test)
    k = 4
    metrics = {"coverage": np.array([0.96, 0.94, 0.99, 0.99]), "force_in_band_fraction": np.full(k, 0.95)}
    batch = EpisodeBatch(np.zeros((k, 1)), np.zeros(k), np.zeros((k, 1)), np.array([True, True, True, False]),
                         np.zeros(k, int), metrics)
    assert success(batch) is None                      # no is_success: none made up from the task's metrics
    given = EpisodeBatch(batch.actions, batch.returns, batch.cost_traces, batch.valid, batch.seeds, metrics,
                         success=np.array([False, True, True, False]))
    assert success(given).tolist() == [False, True, True, False]


@pytest.mark.parametrize("agent", ["creps", "cpi2"])
def test_contextual_training_run_on_the_tracking_task(tmp_path, agent):
    config = TrainConfig(agent=agent, updates=4, rollouts=8, seed=1, env_id=TRACKING_ID, eval_episodes=6, eval_every=2,
                         env_kwargs={"n_periodic": 10, "n_transient": 10, "duration": 4.0, "context_range": 0.03},
                         options={"sigma": 0.05}, shared_context=False)
    run = train(config, tmp_path / agent)
    records = run.read_log()
    assert [r["episodes"] for r in records] == [0, 8, 16, 24, 32]
    evaluated = [r for r in records if r.get("eval_return_mean") is not None]
    assert [r["update"] for r in evaluated] == [0, 2, 4]
    assert evaluated[-1]["eval_return_mean"] > evaluated[0]["eval_return_mean"]
    from rdmp_gym.agents.report import evaluate_run

    result = evaluate_run(run.path, 3)
    assert result["policy"] == "last" and len(result["trained"]["jerk_ratio"]) == 3
    assert result["imitation"]["jerk_ratio_mean"] == pytest.approx(1.0)


def test_sac_trains_on_the_one_step_task(tmp_path):
    import torch

    torch.set_num_threads(1)
    config = TrainConfig(agent="sac", updates=2, rollouts=4, seed=0, env_id=TRACKING_ID, eval_episodes=2,
                         env_kwargs={"n_periodic": 10, "n_transient": 10, "duration": 4.0, "context_range": 0.03},
                         options={"sigma": 0.05, "batch_size": 4})
    records = train(config, tmp_path / "sac").read_log()
    assert [r["episodes"] for r in records] == [0, 4, 8]
    assert records[0]["exploration"] == pytest.approx(0.05, rel=1e-3)
    assert all(np.isfinite(r["eval_return_mean"]) and np.isfinite(r["return_mean"]) for r in records[1:])
    from rdmp_gym.agents.report import evaluate_run

    assert np.isfinite(evaluate_run(tmp_path / "sac", 2)["trained"]["return_mean"])


def test_sac_leaves_no_sb3_folder_in_the_temporary_directory(tmp_path, monkeypatch):
    """SB3's default logger makes an ``SB3-<date>`` folder at every ``learn()``; the agents set their own."""
    from rdmp_gym.agents.sb3 import SACAgent
    from rdmp_gym.agents.tasks import TaskSpec
    from rdmp_gym.envs.registration import TRACKING_ID as TRACKING

    monkeypatch.setenv("SB3_LOGDIR", str(tmp_path / "sb3"))     # where SB3's default logger would write
    spec = TaskSpec(TRACKING, {"n_periodic": 8, "n_transient": 8, "duration": 2.0})
    agent = SACAgent(spec, np.zeros(spec.make().action_space.shape[0]), rollouts=2, seed=0)
    try:
        agent.train_update()
    finally:
        agent.close()
    assert not (tmp_path / "sb3").exists()


def test_gain_groups_make_only_those_actions_depend_on_the_context():
    _, _, learner = _toy("creps", _contextual_target, updates=10, length=0.0, gain_prior=0.01,
                         gain_groups="amplitude")
    assert np.all(learner.gains[: N - 2, 1:] == 0.0)                   # periodic: one θ for every context
    assert np.all(np.abs(learner.gains[N - 2:, 1:]) > 1e-3)           # amplitude: context gains learned
    assert np.any(learner.gains[: N - 2, 0] != 0.0)                   # ... while the shared θ̄ still moves
    with pytest.raises(ValueError, match="gain_groups"):
        make_learner("creps", np.zeros(N), 10, np.random.default_rng(0), {"gain_groups": "initial"}, space=_space())


def test_features_select_context_fields_by_name():
    space = SearchSpace({"periodic": slice(0, N - 2), "amplitude": slice(N - 2, N)}, 2, np.zeros(3), np.ones(3),
                        context_names=("patch_size", "patch_size", "table_height"))
    learner = make_learner("creps", np.zeros(N), 10, np.random.default_rng(0), {"features": "patch_size"}, space=space)
    assert learner.features(np.ones((4, 3))).shape == (4, 3)           # constant + the two patch sides
    assert learner.state_dict()["context_scale"].tolist() == [1.0, 1.0, 0.0]
    with pytest.raises(ValueError, match="features"):
        make_learner("creps", np.zeros(N), 10, np.random.default_rng(0), {"features": "patch_sise"}, space=space)
    with pytest.raises(ValueError, match="features"):                  # an env without named fields
        make_learner("creps", np.zeros(N), 10, np.random.default_rng(0), {"features": "patch_size"}, space=_space())


def test_the_wiping_task_defaults_of_the_contextual_searches_are_written_into_the_config():
    from rdmp_gym.agents.learners.contextual import AmplitudeConfig, CPI2Config, RandomReturnConfig
    from rdmp_gym.agents.tasks import WIPE_ID
    from rdmp_gym.envs.registration import learner_defaults

    defaults = learner_defaults(WIPE_ID)["cpi2"]
    config = TrainConfig(agent="cpi2", env_id=WIPE_ID, options={"sigma_factors": {"approach": 2}})
    assert config.options == CPI2Config.from_dict({**defaults, "sigma_factors": {"approach": 2.0}})  # the run's wins
    assert config.options.gain_groups == ("amplitude", "approach")                  # typed: lists, not comma strings
    assert TrainConfig.from_dict(config.to_dict()) == config                       # and it round-trips
    control = TrainConfig(agent="random", env_id=WIPE_ID).options
    assert control == RandomReturnConfig.from_dict(defaults)                       # the control explores alike
    assert TrainConfig(agent="amplitude", env_id=WIPE_ID).options == AmplitudeConfig()
    assert TrainConfig(agent="cpi2", env_id=WIPE_ID, env_kwargs={"groups": ["periodic"]}).options == CPI2Config()
    assert TrainConfig(agent="cpi2", env_id=TRACKING_ID).options == CPI2Config()
    given = CPI2Config(sigma=0.2)                                                   # a typed object is used as given
    assert TrainConfig(agent="cpi2", options=given).options is given
    old = {**config.to_dict(), "options": {"gain_groups": "amplitude,approach", "sigma_factors": "approach=3"}}
    assert TrainConfig.from_dict(old).options.sigma_factors == {"approach": 3.0}  # a config.json of earlier versions
    with pytest.raises(TypeError, match=r"cpi2\.sigma"):
        TrainConfig(agent="cpi2", options={"sigma": "big"})
    fixed = {"weighting": "pi2", "contextual": True, "random_returns": False, "max_sigma": 0.6}
    saved = {**config.to_dict(), "options": {**config.options.to_dict(), **fixed}}
    assert TrainConfig.from_dict(saved) == config                                # what cpi2 always runs with
    with pytest.raises(ValueError, match=r"cpi2\.max_sigma"):
        TrainConfig.from_dict({**saved, "options": {**saved["options"], "max_sigma": 0.4}})


def test_bbrl_antithetic_pairs_share_their_contexts_on_a_task():
    """With ``antithetic`` the training loop runs every reset seed twice in a row (tracking task)."""
    from rdmp_gym.agents.pool import Evaluator
    from rdmp_gym.agents.protocol import context_observations
    from rdmp_gym.agents.tasks import TaskSpec
    from rdmp_gym.agents.training import ESAgent

    spec = TaskSpec(TRACKING_ID, {"n_periodic": 8, "n_transient": 8, "duration": 2.0, "context_range": 0.03})
    with Evaluator(spec, 1) as evaluator:
        space = SearchSpace.from_env(evaluator.env, context_observations(evaluator.env, np.arange(8), spec.options()))
        n = evaluator.env.action_space.shape[0]
        learner = make_learner("bbrl", np.zeros(n), 4, np.random.default_rng(0), {"antithetic": True}, space=space)
        agent = ESAgent(learner, evaluator, np.random.default_rng(1), shared_context=False)
        first, second = agent.train_update(), agent.train_update()
    for batch in (first, second):
        assert np.array_equal(batch.seeds[0::2], batch.seeds[1::2]) and np.unique(batch.seeds).size == 2
        assert not np.array_equal(batch.actions[0], batch.actions[1])           # mirrored, not repeated
