"""The cycle-by-cycle search: its trust region, its per-cycle credit and its policy, on a task without MuJoCo."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from rdmp_gym.agents.learners.cycle_search import (
    CycleBatch,
    CycleSearch,
    CycleSearchConfig,
    act_with,
    trust_region_weights,
)

CYCLES, ACTIONS = 3, 4


@given(st.lists(st.integers(-20, 20).map(lambda value: 0.5 * value), min_size=3, max_size=40), st.floats(0.05, 2.0))
@settings(max_examples=60, deadline=None)
def test_the_weights_keep_the_kl_bound_and_prefer_lower_advantages(advantages, epsilon):
    advantages = np.array(advantages)
    weights = trust_region_weights(advantages, epsilon)
    assert np.isclose(weights.sum(), 1.0) and np.all(weights >= 0)
    kl = float(np.sum(weights * np.log(np.maximum(weights * weights.size, 1e-300))))
    assert kl <= epsilon + 1e-4
    order = np.argsort(advantages)
    assert np.all(np.diff(weights[order]) <= 1e-12)          # a lower advantage never gets less weight
    sharpest = np.log(advantages.size / np.sum(advantages == advantages.min()))   # KL with all weight on the best
    if np.ptp(advantages) > 0 and sharpest > epsilon + 0.1:
        assert kl == pytest.approx(epsilon, abs=1e-3)         # the bound is reached where it can be


def _targets(context: np.ndarray) -> np.ndarray:
    """``[C, n]`` the best action of each cycle in a context (a different one per cycle)."""
    return np.stack([0.5 * np.tanh(context[0] + cycle) * np.ones(ACTIONS) * (-1) ** cycle for cycle in range(CYCLES)])


def _batch(search: CycleSearch, rng: np.random.Generator, count: int, explore: bool = True) -> CycleBatch:
    """``count`` episodes of a task where cycle c costs ``|a_c - target_c(context)|^2``."""
    observations = np.zeros((count, CYCLES, 2))
    spent, costs = np.zeros((count, CYCLES)), np.zeros(count)
    shared, own = search.exploration(count) if explore else (np.zeros((count, ACTIONS)),
                                                             np.zeros((count, CYCLES, ACTIONS)))
    for i in range(count):
        context, previous = rng.uniform(-1, 1), None
        target = _targets(np.array([context]))
        for cycle in range(CYCLES):
            observations[i, cycle] = (context, cycle / CYCLES)
            spent[i, cycle] = costs[i]
            previous = search.act(cycle, observations[i, cycle], previous, shared[i] + own[i, cycle])
            costs[i] += float(np.sum((previous - target[cycle]) ** 2))
    return CycleBatch(observations, costs, spent, shared, own)


def _search(seed: int, active: np.ndarray | None = None) -> CycleSearch:
    active = np.ones((CYCLES, ACTIONS), dtype=bool) if active is None else active
    config = CycleSearchConfig(sigma=0.3, length=0.0, reuse=2, decay=0.95)
    return CycleSearch(ACTIONS, 1, active, np.zeros(2), np.array([0.6, 0.3]), [(slice(0, ACTIONS), None)], config,
                       np.random.default_rng(seed))


def _train(seed: int, random_costs: bool) -> float:
    search, rng = _search(seed), np.random.default_rng(100 + seed)
    for _ in range(40):
        batch = _batch(search, rng, 16)
        if random_costs:
            batch = CycleBatch(batch.observations, rng.standard_normal(16), batch.spent, batch.shared, batch.own)
        search.update(batch)
    return float(np.mean(_batch(search, np.random.default_rng(999), 64, explore=False).costs))


def test_per_cycle_credit_learns_a_policy_for_each_cycle_that_random_costs_do_not():
    start = float(np.mean(_batch(_search(0), np.random.default_rng(999), 64, explore=False).costs))
    learned = [_train(seed, random_costs=False) for seed in range(3)]
    control = [_train(seed, random_costs=True) for seed in range(3)]
    assert max(learned) < 0.2 * start
    assert max(learned) < 0.5 * min(control)


def test_the_same_seed_gives_the_same_policy():
    first, second = _search(3), _search(3)
    for search in (first, second):
        rng = np.random.default_rng(5)
        for _ in range(3):
            search.update(_batch(search, rng, 8))
    assert np.array_equal(first.maps, second.maps) and first.sigma == second.sigma


def test_a_dimension_that_does_not_act_in_a_cycle_keeps_the_previous_value():
    active = np.ones((CYCLES, ACTIONS), dtype=bool)
    active[1:, :2] = False                                   # e.g. a transient's weights after the transient
    search = _search(0, active)
    search.maps[:, :, 0] = np.linspace(-0.5, 0.5, CYCLES)[:, None]
    first = search.act(0, np.zeros(2), None)
    second = search.act(1, np.zeros(2), first)
    assert np.array_equal(second[:2], first[:2]) and not np.array_equal(second[2:], first[2:])
    assert np.array_equal(act_with(search.policy(), 1, np.zeros(2), first), second)
    rng = np.random.default_rng(1)
    search.update(_batch(search, rng, 8))
    assert np.all(search.maps[1:, :2, 0] == np.linspace(-0.5, 0.5, CYCLES)[1:, None])     # never refitted


def test_bad_inputs_are_refused_by_name():
    with pytest.raises(ValueError, match="active"):
        CycleSearch(ACTIONS, 1, np.ones((CYCLES, ACTIONS + 1), bool), np.zeros(2), np.ones(2), [],
                    CycleSearchConfig(), np.random.default_rng(0))
    with pytest.raises(ValueError, match="context_size"):
        CycleSearch(ACTIONS, 3, np.ones((CYCLES, ACTIONS), bool), np.zeros(2), np.ones(2), [], CycleSearchConfig(),
                    np.random.default_rng(0))
    with pytest.raises(ValueError, match="sigma"):
        CycleSearchConfig(sigma=0.0)
    with pytest.raises(ValueError, match="batch"):
        CycleBatch(np.zeros((2, 3, 2)), np.zeros(2), np.zeros((2, 3)), np.zeros((2, 4)), np.zeros((2, 2, 4)))
    with pytest.raises(ValueError, match="batch"):
        CycleBatch(np.zeros((2, 3, 2)), np.zeros(2), np.zeros((2, 3)), np.zeros((2, 5)), np.zeros((2, 3, 4)))
    with pytest.raises(ValueError, match="costs"):
        CycleBatch(np.zeros((2, 3, 2)), np.array([0.0, np.nan]), np.zeros((2, 3)), np.zeros((2, 4)),
                   np.zeros((2, 3, 4)))


def _configured(**changes) -> CycleSearch:
    config = CycleSearchConfig(sigma=0.3, length=0.0, reuse=2, decay=0.95, **changes)
    return CycleSearch(ACTIONS, 1, np.ones((CYCLES, ACTIONS), dtype=bool), np.zeros(2), np.array([0.6, 0.3]),
                       [(slice(0, ACTIONS), None)], config, np.random.default_rng(3))


def test_pooled_cycles_share_one_map_and_the_first_keeps_its_own():
    search, rng = _configured(pooled=True, shared=0.0), np.random.default_rng(4)
    for _ in range(3):
        search.update(_batch(search, rng, 16))
    assert np.array_equal(search.maps[1], search.maps[2])
    assert not np.allclose(search.maps[0], search.maps[1])


def test_feedback_keep_decides_whether_the_feedback_gains_accumulate():
    kept, fresh = _configured(feedback_keep=1.0), _configured(feedback_keep=0.0)
    rng_kept, rng_fresh = np.random.default_rng(5), np.random.default_rng(5)
    for _ in range(2):
        first = _batch(kept, rng_kept, 16)
        fresh_batch = _batch(fresh, rng_fresh, 16)
        before = kept.maps[:, :, 2:].copy()
        kept.update(first)
        fresh.update(fresh_batch)
    change = fresh.maps[:, :, 2:]                    # the last update's own feedback change
    assert np.allclose(kept.maps[:, :, 2:], before + change)
    with pytest.raises(ValueError, match="feedback_keep"):
        CycleSearchConfig(feedback_keep=1.5)
