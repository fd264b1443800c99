"""``bbrl_segments``: each action dimension is credited with the cost of the segments it acts in, its critic
learns the segment costs of the contexts from earlier batches, the trust region holds, resume is exact, and bad
options are clear errors (MuJoCo-free toys; the wiping tasks are in the benchmarks)."""

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np
import pytest
import torch
from hypothesis import given, settings
from hypothesis import strategies as st
from rdmp_gym.agents.learners import EpisodeBatch, SearchSpace, make_learner, policy_from_state
from rdmp_gym.agents.learners.segment_bbrl import (
    segment_activation,
    segment_costs,
    segment_starts,
    segment_weights,
)

torch.set_num_threads(1)
STEPS, SEGMENTS, N = 80, 8, 16
#: dimension i acts (a bump) in segment i // 2 of the toy's 8 segments of 10 steps
ACTIVATION = np.exp(-0.5 * ((np.arange(STEPS)[:, None] - (10 * (np.arange(N) // 2) + 5)) / 2.5) ** 2)
#: only segment 5 costs anything, and only dimensions 10 and 11 act there
TARGET = 0.5
RELEVANT = np.array([10, 11])


def _space(time_weights=ACTIVATION):
    return SearchSpace({"periodic": slice(0, N)}, 1, np.zeros(2), np.ones(2), time_weights)


def _learner(seed=0, agent="bbrl_segments", **options):
    options = {"segments": SEGMENTS, "length": 0.0, "epsilon": 0.2, **options} if agent == "bbrl_segments" \
        else {"length": 0.0, "epsilon": 0.2, **options}
    return make_learner(agent, np.zeros(N), 10, np.random.default_rng(seed), options, space=_space())


def _traces(actions, rng, noise):
    """``[K, T]`` a cost only in segment 5 (steps 50-59): the squared miss of the relevant dimensions; plus, in
    every other step, noise that no action explains."""
    traces = noise * rng.standard_normal((len(actions), STEPS)) ** 2 / STEPS
    traces[:, 50:60] = 0.0
    traces[:, 55] += np.sum((actions[:, RELEVANT] - TARGET) ** 2, axis=1)
    return traces


def _batch(actions, traces, seeds=None):
    k = len(actions)
    costs = traces.sum(axis=1)
    return EpisodeBatch(actions, -costs, traces, np.ones(k, dtype=bool),
                        np.arange(k, dtype=np.int64) if seeds is None else seeds)


def _run(learner, updates, seed=0, noise=2.0):
    """``updates`` updates on the toy; returns the KL of each."""
    rng = np.random.default_rng(200 + seed)
    kls = []
    for _ in range(updates):
        actions = learner.ask(rng.uniform(-1, 1, (10, 2)))
        learner.tell(_batch(actions, _traces(actions, rng, noise)))
        kls.append(learner.last_kl)
    return np.array(kls)


def test_segments_split_the_steps_and_keep_the_episode_cost():
    starts = segment_starts(STEPS, SEGMENTS)
    np.testing.assert_array_equal(starts, np.arange(0, 80, 10))
    assert segment_starts(5, 16).tolist() == [0, 1, 2, 3, 4]              # never more segments than steps
    traces = np.random.default_rng(0).random((3, STEPS))
    costs = traces.sum(axis=1) + np.array([0.0, 1.0, -2.0])              # a part the traces do not hold
    parts = segment_costs(costs, traces, starts)
    np.testing.assert_allclose(parts.sum(axis=1), costs)
    np.testing.assert_allclose(parts[:, :-1], traces[:, :70].reshape(3, 7, 10).sum(axis=2))


@settings(max_examples=30, deadline=None)
@given(steps=st.integers(1, 300), segments=st.integers(1, 40))
def test_segment_starts_cover_every_step_once(steps, segments):
    starts = segment_starts(steps, segments)
    assert starts[0] == 0 and np.all(np.diff(starts) > 0) and starts[-1] < steps
    assert len(starts) == min(steps, segments)


def test_activation_is_relative_to_each_dimensions_most_active_segment():
    starts = segment_starts(STEPS, SEGMENTS)
    weights = np.c_[ACTIVATION, np.ones(STEPS), np.zeros(STEPS)]          # + one acting throughout, one never
    activation = segment_activation(weights, starts)
    assert activation.shape == (SEGMENTS, N + 2)
    np.testing.assert_allclose(activation.max(axis=0), 1.0)
    assert np.all(activation.argmax(axis=0)[:N] == np.arange(N) // 2)
    np.testing.assert_allclose(activation[:, N:], 1.0)
    assert activation[0, 10] < 1e-6                                       # a segment-5 weight, far from segment 0


def test_a_dimension_is_judged_only_by_the_segments_it_acts_in():
    """Costs only in segment 5: with no episode share, a dimension acting elsewhere gets exactly uniform weights,
    one acting there prefers the cheapest sample of segment 5, though another sample is cheapest overall."""
    parts = np.zeros((6, SEGMENTS))
    parts[:, 5] = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0]
    parts[:, 0] = [9.0, 0.0, 0.0, 0.0, 0.0, 0.0]                          # sample 0 is the dearest episode
    activation = segment_activation(ACTIVATION, segment_starts(STEPS, SEGMENTS))
    per_dimension, episode = segment_weights(parts, np.zeros((6, 2)), activation, h=10.0,
                                             ridge=1.0, episode_share=0.0, common_scale=True)
    np.testing.assert_allclose(per_dimension.sum(axis=1), 1.0)
    assert per_dimension[10].argmax() == 0 and per_dimension[11].argmax() == 0
    elsewhere = [i for i in range(N) if i // 2 in (2, 3)]                 # two segments from both costs
    np.testing.assert_allclose(per_dimension[elsewhere], 1.0 / 6, atol=1e-3)
    assert episode.argmax() == 1
    mixed, _ = segment_weights(parts, np.zeros((6, 2)), activation, 10.0, 1.0, episode_share=1.0)
    np.testing.assert_allclose(mixed, np.repeat(episode[None], N, axis=0))


def _every_segment_costs(actions):
    """``[K, T]`` each segment's cost the squared miss of the two dimensions acting in it (one step each)."""
    traces = np.zeros((len(actions), STEPS))
    np.add.at(traces.T, 10 * (np.arange(N) // 2) + 5, ((actions - TARGETS) ** 2).T)
    return traces


TARGETS = np.random.default_rng(4).uniform(-0.5, 0.5, N)


def _miss_after(learner, updates, seed):
    rng = np.random.default_rng(seed)
    for _ in range(updates):
        actions = learner.ask(rng.uniform(-1, 1, (10, 2)))
        learner.tell(_batch(actions, _every_segment_costs(actions)))
    return np.abs(learner.policy_actions(np.zeros((1, 2)))[0] - TARGETS).mean()


def test_segment_credit_learns_faster_than_one_advantage_per_episode():
    """Every segment's cost depends on its own two dimensions: judged by the episode, each dimension's signal is
    drowned by the other seven segments' exploration; judged by its segment, it is not (3 seeds, 20 updates)."""
    segment = np.mean([_miss_after(_learner(seed, baseline="ridge"), 20, seed) for seed in range(3)])
    episode = np.mean([_miss_after(_learner(seed, baseline="ridge", credit="episode"), 20, seed) for seed in range(3)])
    start = np.abs(TARGETS).mean()
    assert segment < 0.4 * start
    assert segment < 0.8 * episode


def test_the_critic_learns_which_contexts_cost_more():
    """A context-dependent cost in segment 2 (no action changes it): the critic's prediction for it follows."""
    learner = _learner(history=5, value_epochs=200)
    rng = np.random.default_rng(3)
    for _ in range(8):
        contexts = rng.uniform(-1, 1, (10, 2))
        actions = learner.ask(contexts)
        traces = _traces(actions, rng, noise=0.0)
        traces[:, 25] += np.sin(3 * contexts[:, 0])
        learner.tell(_batch(actions, traces))
    grid = np.c_[np.linspace(-1, 1, 21), np.zeros(21)]
    with torch.no_grad():
        predicted = learner.value(torch.as_tensor(grid)).numpy()[:, 2]
    assert np.corrcoef(predicted, np.sin(3 * grid[:, 0]))[0, 1] > 0.9


@pytest.mark.parametrize("epsilon", [0.01, 0.2])
def test_every_update_stays_within_the_trust_region(epsilon):
    kls = _run(_learner(epsilon=epsilon, learning_rate=0.1), 6)
    assert np.all(kls <= epsilon + 1e-9)
    assert np.mean(kls > 0.2 * epsilon) > 0.5


def test_resume_is_exact_with_the_critic_and_its_history():
    learner = _learner(history=3)
    _run(learner, 5)
    twin = _learner(seed=99, history=3)
    twin.load_state_dict(learner.state_dict())
    asked = {}
    for name, agent in (("original", learner), ("resumed", twin)):
        rng, asked[name] = np.random.default_rng(9), []
        for _ in range(3):
            actions = agent.ask(rng.uniform(-1, 1, (10, 2)))
            agent.tell(_batch(actions, _traces(actions, rng, 1.0)))
            asked[name].append(actions)
    np.testing.assert_array_equal(asked["resumed"], asked["original"])
    contexts = np.random.default_rng(7).uniform(-1, 1, (5, 2))
    np.testing.assert_array_equal(twin.policy_actions(contexts), learner.policy_actions(contexts))
    np.testing.assert_allclose(policy_from_state(learner.state_dict(), contexts), learner.policy_actions(contexts),
                               atol=1e-12)


def test_bad_options_and_inputs_raise_clear_errors():
    with pytest.raises(ValueError, match="segments"):
        _learner(segments=0)
    with pytest.raises(ValueError, match="episode_share"):
        _learner(episode_share=1.5)
    with pytest.raises(ValueError, match="time_weights"):
        make_learner("bbrl_segments", np.zeros(N), 10, np.random.default_rng(0), space=_space(None))
    with pytest.raises(ValueError, match="state"):
        _learner().load_state_dict(_learner(agent="bbrl").state_dict())
    learner = _learner()
    actions = learner.ask(np.zeros((10, 2)))
    with pytest.raises(ValueError, match="cost_traces"):
        learner.tell(_batch(actions, np.zeros((10, STEPS + 1))))
