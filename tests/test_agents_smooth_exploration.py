"""Smooth exploration for PI² and CMA-ES (``length`` > 0): the explored weights are correlated along the
movement, so exploring does not make the paths jagged (MuJoCo-free)."""

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np
import pytest
from rdmp_gym.agents.learners import EpisodeBatch, SearchSpace, make_learner
from rdmp_gym.agents.tasks import WIPE_ID, WIPE_V2_ID, task_options

N, WEIGHTS = 42, 20            # 2 DoF x 20 periodic weights, then 2 amplitude factors


def _space():
    return SearchSpace({"periodic": slice(0, 2 * WEIGHTS), "amplitude": slice(2 * WEIGHTS, N)}, 2, np.zeros(1),
                       np.ones(1))


def _roughness(actions):
    """Mean squared circular second difference of the first DoF's periodic weights, per unit variance."""
    block = actions[:, :WEIGHTS]
    second = np.roll(block, -1, axis=1) - 2 * block + np.roll(block, 1, axis=1)
    return float(np.mean(second**2) / np.mean(block**2))


@pytest.mark.parametrize("agent", ["pi2", "cmaes"])
def test_smooth_exploration_is_far_smoother_than_independent_noise(agent):
    weights = np.ones((5, N))
    rough, smooth = ([make_learner(agent, np.zeros(N), 200, np.random.default_rng(0),
                                   {"sigma": 0.2, "length": length}, time_weights=weights, space=_space()).ask()
                      for length in (0.0, 5.0)])
    assert _roughness(smooth) < 0.1 * _roughness(rough)
    assert 0.5 * 0.2 < np.std(smooth[:, :2 * WEIGHTS]) < 1.5 * 0.2        # about the same size (CMA-ES: 0.2 too)
    assert np.std(smooth[:, 2 * WEIGHTS:]) == pytest.approx(0.2, rel=0.3)  # single factors stay independent


def test_smooth_exploration_needs_the_layout():
    with pytest.raises(ValueError, match="space"):
        make_learner("cmaes", np.zeros(N), 10, np.random.default_rng(0), {"length": 5.0})
    with pytest.raises(ValueError, match="length"):
        make_learner("pi2", np.zeros(N), 10, np.random.default_rng(0), {"length": -1.0},
                     time_weights=np.ones((5, N)), space=_space())


def test_smooth_cmaes_resumes_exactly_and_keeps_the_box():
    options = {"sigma": 0.5, "length": 5.0}
    learner = make_learner("cmaes", np.full(N, 0.9), 8, np.random.default_rng(1), options, space=_space())
    rng = np.random.default_rng(2)
    for _ in range(3):
        actions = learner.ask()
        assert np.all(np.abs(actions) <= 1.0)
        learner.tell(_batch(actions, rng.standard_normal(8)))
    twin = make_learner("cmaes", np.full(N, 0.9), 8, np.random.default_rng(9), options, space=_space())
    twin.load_state_dict(learner.state_dict())
    np.testing.assert_array_equal(twin.ask(), learner.ask())


def _batch(actions, returns):
    k = len(returns)
    return EpisodeBatch(actions, np.asarray(returns, dtype=float), np.zeros((k, 1)), np.ones(k, dtype=bool),
                        np.zeros(k, dtype=np.int64))


def test_the_v2_task_explores_smoothly_by_default_and_v1_keeps_its_published_settings():
    for agent in ("pi2", "cmaes"):
        assert task_options(WIPE_V2_ID, agent, {})["length"] == 5.0
        assert "length" not in task_options(WIPE_ID, agent, {})
        assert task_options(WIPE_V2_ID, agent, {"length": 0.0})["length"] == 0.0
