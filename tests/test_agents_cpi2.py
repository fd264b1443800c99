"""Contextual PI² (``cpi2``; ``plain_prior`` in the benchmarks is ``cpi2`` without hand structure): per-step credit
on a toy where only one segment of the path matters, the trust region of its update, exact resume and clear errors
(MuJoCo-free)."""

import os
from dataclasses import dataclass
from typing import ClassVar

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np
import pytest
from rdmp_gym.agents.learners import EpisodeBatch, SearchSpace, make_learner, policy_from_state
from rdmp_gym.agents.learners.contextual import MAX_SIGMA, ContextualSearch, CPI2Config, CPIBBConfig

N, T, K = 12, 20, 10
EARLY, LATE = slice(0, N // 2), slice(N // 2, N)
TARGET = np.linspace(-0.4, 0.4, N)


def _activation() -> np.ndarray:
    """``[T, N]``: the first half of the weights acts in the first half of the steps, the rest in the second."""
    weights = np.zeros((T, N))
    weights[: T // 2, EARLY] = 1.0
    weights[T // 2:, LATE] = 1.0
    return weights


def _space(time_weights=None) -> SearchSpace:
    weights = _activation() if time_weights is None else time_weights
    return SearchSpace({"first": EARLY, "second": LATE}, 1, np.zeros(2), np.ones(2), time_weights=weights)


def _learner(seed=0, time_weights=None, **options):
    return make_learner("cpi2", np.zeros(N), K, np.random.default_rng(seed), {"length": 0.0, **options},
                        space=_space(time_weights))


@dataclass(frozen=True)
class _SharedPI2(CPI2Config):
    """``cpi2`` with one θ for every context."""

    contextual: ClassVar[bool] = False


@dataclass(frozen=True)
class _SharedPIBB(CPIBBConfig):
    """``cpibb`` with one θ for every context."""

    contextual: ClassVar[bool] = False


def _shared(config: type, seed: int) -> ContextualSearch:
    return ContextualSearch(np.zeros(N), K, np.random.default_rng(seed), _space(), config(length=0.0))


def _traces(actions: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """``[K, T]``: the first segment costs a large draw that no action changes; the second segment costs the
    distance of the late weights from their target (the only part of the path the actions can improve)."""
    traces = np.zeros((actions.shape[0], T))
    traces[:, : T // 2] = rng.uniform(0, 1.0, (actions.shape[0], 1)) / (T // 2)
    late = np.sum((actions[:, LATE] - TARGET[LATE]) ** 2, axis=1)
    traces[:, T // 2:] = late[:, None] / (T - T // 2)
    return traces


def _batch(actions: np.ndarray, traces: np.ndarray) -> EpisodeBatch:
    k = actions.shape[0]
    return EpisodeBatch(actions, -traces.sum(axis=1), traces, np.ones(k, dtype=bool), np.zeros(k, dtype=np.int64))


def _train(learner, updates: int, seed: int = 0) -> float:
    """The late weights' squared distance from their target after ``updates`` updates of the toy."""
    rng = np.random.default_rng(50 + seed)
    for _ in range(updates):
        actions = learner.ask(rng.uniform(-1, 1, (K, 2)))
        learner.tell(_batch(actions, _traces(actions, rng)))
    return float(np.sum((learner.mean[LATE] - TARGET[LATE]) ** 2))


def test_per_step_credit_ignores_the_cost_of_a_segment_no_weight_acts_in():
    """The late weights are judged by the cost from step T/2 on, which the early draw does not reach: per-step
    credit (PI²'s weighting) learns them several times closer than one weight per episode (PI^BB's), in every
    seed (one θ for every context, both)."""
    start = float(np.sum(TARGET[LATE] ** 2))
    per_step = np.array([_train(_shared(_SharedPI2, s), 15, s) for s in range(3)])
    per_episode = np.array([_train(_shared(_SharedPIBB, s), 15, s) for s in range(3)])
    assert np.all(per_step < 0.2 * start)
    assert np.all(per_step < 0.25 * per_episode)


def test_a_stronger_gain_prior_keeps_the_gains_nearer_their_previous_value():
    """The update's trust region: the ridge ``gain_prior`` pulls the context gains toward the old ones, so one
    update on the same samples moves them less the stronger it is, and barely at all when it dominates."""
    steps = []
    for prior in (0.1, 10.0, 1e5):
        learner = _learner(gain_prior=prior)
        learner.gains[:, 1:] = 0.3
        before = learner.gains.copy()
        _train(learner, 1)
        steps.append(np.abs(learner.gains[:, 1:] - before[:, 1:]).max())
    assert steps[0] > steps[1] > steps[2]
    assert steps[2] < 1e-3 * steps[0]


def test_the_exploration_stays_within_its_bounds():
    learner = _learner(sigma=0.3, min_sigma=0.05)
    _train(learner, 20)
    assert np.all(learner.sigmas >= 0.05 - 1e-12) and np.all(learner.sigmas <= MAX_SIGMA + 1e-12)
    assert learner.sigmas.min() < 0.3                      # it adapted


def test_resume_continues_bit_for_bit_with_the_cost_traces_of_the_reused_batches():
    learner = _learner(reuse=3)
    _train(learner, 4)
    twin = _learner(reuse=3, seed=99)
    twin.load_state_dict(learner.state_dict())
    _train(learner, 3, seed=7)
    _train(twin, 3, seed=7)
    np.testing.assert_array_equal(twin.gains, learner.gains)
    np.testing.assert_array_equal(twin.sigmas, learner.sigmas)


def test_clear_errors_for_missing_or_misshaped_activations_and_traces():
    with pytest.raises(ValueError, match="time_weights"):
        make_learner("cpi2", np.zeros(N), K, np.random.default_rng(0),
                     space=SearchSpace({"all": slice(0, N)}, 1, np.zeros(2), np.ones(2)))
    with pytest.raises(ValueError, match="time_weights"):
        _learner(time_weights=np.ones((T, N - 1)))
    learner = _learner()
    actions = learner.ask(np.zeros((K, 2)))
    with pytest.raises(ValueError, match="cost_traces"):
        learner.tell(_batch(actions, np.zeros((K, T + 1))))
    with pytest.raises(ValueError, match="gain_prior"):
        _learner(gain_prior=0.0)
    learner.tell(_batch(actions, np.zeros((K, T))))            # the refused batch left the learner as it was
    assert learner.state_dict()["buffer"]["sizes"].tolist() == [K]


def test_fourier_features_extend_the_context_and_travel_with_the_state():
    """``fourier_features`` D adds D bounded columns after ``[1, φ(s)]``; the state carries their draw (a twin
    built from another generator acts the same after loading it); a linear learner's state has no such entry."""
    learner = _learner(fourier_features=16, fourier_length=0.5)
    contexts = np.random.default_rng(3).uniform(-1, 1, (K, 2))
    x = learner.features(contexts)
    assert x.shape == (K, 1 + 2 + 16)
    np.testing.assert_array_equal(x[:, 1:3], contexts)
    assert np.all(np.abs(x[:, 3:]) <= np.sqrt(2 / 16) + 1e-12) and x[:, 3:].std() > 0.05
    _train(learner, 2)
    twin = _learner(fourier_features=16, fourier_length=0.5, seed=42)
    assert not np.allclose(twin.features(contexts), learner.features(contexts))
    twin.load_state_dict(learner.state_dict())
    np.testing.assert_array_equal(twin.policy_actions(contexts), learner.policy_actions(contexts))
    np.testing.assert_array_equal(policy_from_state(learner.state_dict(), contexts), learner.policy_actions(contexts))
    assert "fourier_phases" not in _learner().state_dict()
    with pytest.raises(ValueError, match="state"):
        _learner(fourier_features=8).load_state_dict(learner.state_dict())
    with pytest.raises(ValueError, match="fourier_features"):
        _learner(fourier_features=-1)
    with pytest.raises(ValueError, match="fourier_length"):
        _learner(fourier_features=4, fourier_length=0.0)
