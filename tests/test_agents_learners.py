"""Learners on a MuJoCo-free DMP task: improvement, PI²'s time weighting, determinism, state, bad options."""

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np
import pytest
from rdmp_gym.agents.learners import PI2, EpisodeBatch, cost_weights, make_learner
from rdmp_gym.envs.tracking import TrackingEnv


@pytest.fixture(scope="module")
def task():
    return TrackingEnv()


def _batch(env, actions):
    results = []
    for action in actions:
        env.reset(seed=0)
        results.append(env.step(action))
    k = len(actions)
    return EpisodeBatch(actions=np.asarray(actions, dtype=np.float64),
                        returns=np.array([r[1] for r in results]),
                        cost_traces=np.stack([r[4]["cost_trace"] for r in results]),
                        valid=np.ones(k, dtype=bool), seeds=np.zeros(k, dtype=np.int64))


def _policy_return(env, action):
    env.reset(seed=0)
    return env.step(action)[1]


def _learn(env, agent, start, updates, options=None, seed=0):
    learner = make_learner(agent, start, 10, np.random.default_rng(seed), options, env.action_time_weights())
    history = [_policy_return(env, learner.mean)]
    for _ in range(updates):
        learner.tell(_batch(env, learner.ask()))
        history.append(_policy_return(env, learner.mean))
    return learner, np.array(history)


def _perturbed_start(env, scale=0.3):
    return np.clip(scale * np.random.default_rng(1).standard_normal(env.action_space.shape[0]), -1, 1)


def test_cost_weights_prefer_low_cost_and_sum_to_one():
    costs = np.array([[3.0, 1.0, 2.0], [5.0, 5.0, 5.0]])
    weights = cost_weights(costs, 10.0)
    np.testing.assert_allclose(weights.sum(axis=1), 1.0)
    assert np.argmax(weights[0]) == 1 and weights[0, 1] > 0.99 * weights[0].max()
    np.testing.assert_allclose(weights[1], 1.0 / 3.0)
    np.testing.assert_allclose(weights[0, 0] / weights[0, 1], np.exp(-10.0))


def test_pi2_improves_from_a_perturbed_start(task):
    start = _perturbed_start(task)
    _, history = _learn(task, "pi2", start, 8, {"sigma": 0.1})
    assert history[0] < -5.0                       # the perturbed start tracks badly (issue 7: smoother, -5.2)
    assert history[-1] > history[0] + 1.5          # a clear improvement within 8 updates (80 episodes)
    assert np.all(np.diff(history) > -0.3)         # and no collapse on the way


def test_cmaes_improves(task):
    start = _perturbed_start(task)
    _, history = _learn(task, "cmaes", start, 20, {"sigma": 0.1})
    assert history[-1] > history[0] + 2.0


@pytest.mark.parametrize("agent", ["pi2", "cmaes"])
def test_same_seed_same_numbers_and_exact_state_restore(task, agent):
    start = _perturbed_start(task)
    first, _ = _learn(task, agent, start, 3, seed=7)
    second, _ = _learn(task, agent, start, 3, seed=7)
    np.testing.assert_array_equal(first.mean, second.mean)
    state = first.state_dict()
    expected_ask = first.ask()
    restored = make_learner(agent, np.zeros(start.size), 10, np.random.default_rng(99), None,
                            task.action_time_weights())
    restored.load_state_dict(state)
    np.testing.assert_array_equal(restored.ask(), expected_ask)
    assert restored.updates == 3 and restored.exploration == pytest.approx(first.exploration)


def test_pi2_update_is_the_time_weighted_average_of_per_step_updates():
    rng = np.random.default_rng(0)
    steps, n, k = 6, 3, 5
    activation = np.zeros((steps, n))
    activation[:3, 0] = 1.0            # a "transient" parameter: active early only
    activation[2:, 1] = 0.5            # a "periodic" parameter: active late only
    # parameter 2 is never active
    learner = PI2(np.zeros(n), k, rng, activation)
    actions = learner.ask()
    traces = rng.uniform(0.0, 1.0, (k, steps))
    returns = -(traces.sum(axis=1) + rng.uniform(0.0, 0.5, k))   # part of the cost is terminal
    batch = EpisodeBatch(actions, returns, traces, np.ones(k, bool), np.zeros(k, np.int64))
    learner.tell(batch)
    # the update written out with loops
    expected = np.zeros(n)
    for i in range(n):
        numerator = denominator = 0.0
        for t in range(steps):
            to_go = traces[:, t:].sum(axis=1) + (-returns - traces.sum(axis=1))
            spread = to_go.max() - to_go.min()
            p = np.exp(-10.0 * (to_go - to_go.min()) / spread)
            p /= p.sum()
            weight = (steps - t) * activation[t, i]
            numerator += weight * (p @ actions[:, i])
            denominator += weight
        expected[i] = numerator / denominator if denominator > 0 else 0.0
    np.testing.assert_allclose(learner.mean, expected, atol=1e-12)
    assert learner.mean[2] == 0.0
    # at t = 0 the weighting is by the total cost: the early parameter leans to the cheapest rollout
    assert learner.exploration == pytest.approx(0.6 * 0.95)


def test_pi2_rejects_cost_traces_of_the_wrong_length(task):
    learner = make_learner("pi2", np.zeros(task.action_space.shape[0]), 10, np.random.default_rng(0), None,
                           task.action_time_weights())
    batch = _batch(task, learner.ask())
    short = EpisodeBatch(batch.actions, batch.returns, batch.cost_traces[:, :-1], batch.valid, batch.seeds)
    with pytest.raises(ValueError, match="cost_traces"):
        learner.tell(short)


def test_bad_learner_options_fail_clearly(task):
    n = task.action_space.shape[0]
    weights = task.action_time_weights()
    rng = np.random.default_rng(0)
    with pytest.raises(ValueError, match="sigmaa"):
        make_learner("pi2", np.zeros(n), 10, rng, {"sigmaa": 0.2}, weights)
    with pytest.raises(TypeError, match=r"cmaes.sigma"):
        make_learner("cmaes", np.zeros(n), 10, rng, {"sigma": "big"})
    with pytest.raises(ValueError, match=r"cmaes\.bounds: not an option of cmaes, which always runs with bounds"):
        make_learner("cmaes", np.zeros(n), 10, rng, {"bounds": "penalty"})
    assert make_learner("cmaes", np.zeros(n), 10, rng, {"bounds": "transform", "diagonal": False}).config \
        == make_learner("cmaes", np.zeros(n), 10, rng).config          # as a saved config.json holds them
    with pytest.raises(ValueError, match=r"pi2.decay"):
        make_learner("pi2", np.zeros(n), 10, rng, {"decay": 1.5}, weights)
    with pytest.raises(ValueError, match="agent"):
        make_learner("reinforce", np.zeros(n), 10, rng)
    with pytest.raises(ValueError, match="time_weights"):
        make_learner("pi2", np.zeros(n), 10, rng)
    with pytest.raises(ValueError, match="rollouts"):
        make_learner("cmaes", np.zeros(n), 1, rng)
    with pytest.raises(ValueError, match="initial_mean"):
        make_learner("cmaes", np.full(n, 2.0), 10, rng)
    with pytest.raises(TypeError, match="rng"):
        make_learner("cmaes", np.zeros(n), 10, 0)


def test_cmaes_tell_needs_the_asked_actions(task):
    learner = make_learner("cmaes", np.zeros(task.action_space.shape[0]), 10, np.random.default_rng(0))
    batch = _batch(task, learner.ask() * 0.5)
    with pytest.raises(ValueError, match="ask"):
        learner.tell(batch)


def test_tracking_task_contract(task):
    obs, _ = task.reset(seed=3)
    assert task.observation_space.contains(obs)
    _, reward, terminated, truncated, info = task.step(np.zeros(task.action_space.shape, np.float32))
    assert terminated is True and truncated is False and isinstance(reward, float)
    np.testing.assert_allclose(-info["cost_trace"].sum(), reward)
    weights = task.action_time_weights()
    assert weights.shape == (info["cost_trace"].size, task.action_space.shape[0])
    assert weights.min() >= 0.0 and weights.max() <= 1.0
    theta = task.action_to_params(np.full(task.action_space.shape, 0.5))
    np.testing.assert_allclose(task.params_to_action(theta), 0.5)
    with pytest.raises(ValueError, match="action"):
        task.step(np.zeros(3))
