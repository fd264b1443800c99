"""Validation that sees what test will: validation contexts spread evenly over the kinds of context an env names."""

from collections import Counter

import gymnasium as gym
import numpy as np
import pytest
import rdmp_gym.envs  # noqa: F401
from bench_agents import _cache_key
from rdmp_gym.agents.protocol import final_test_seeds, stratified_validation_seeds, validation_seeds
from rdmp_gym.agents.training import TrainConfig
from rdmp_gym.envs.contract import TaskContract, contract_of
from rdmp_gym.envs.registration import TRACKING_ID
from rdmp_gym.envs.tasks.wiping.context import CONTEXT_KINDS


class _Kinds(gym.Env):
    """A context is its reset seed; one seed in ``rare`` is of the rare kind."""

    observation_space = gym.spaces.Box(-np.inf, np.inf, (1,))
    action_space = gym.spaces.Box(-1.0, 1.0, (1,))

    def __init__(self, rare: int = 25):
        self.rare = rare

    def reset(self, *, seed=None, options=None):
        return np.array([float(seed)]), {}

    def context_kind(self, observation):
        seed = int(observation[0])
        return "rare" if seed % self.rare == 0 else ("even" if seed % 2 == 0 else "odd")

    def task_contract(self):
        return TaskContract(name="kinds", context_kind=self.context_kind)


def test_a_rare_kind_is_validated_as_often_as_a_common_one():
    env = _Kinds()
    seeds = stratified_validation_seeds(env, 9)
    kinds = Counter(env.context_kind(np.array([s])) for s in seeds)
    assert kinds == {"rare": 3, "even": 3, "odd": 3}
    assert set(seeds) <= set(validation_seeds(400).tolist())              # from the validation range ...
    assert not set(seeds) & set(final_test_seeds(1000).tolist())          # ... never a test context
    np.testing.assert_array_equal(seeds, stratified_validation_seeds(env, 9))   # chosen by the env alone


def test_an_env_without_kinds_gets_the_plain_validation_seeds():
    np.testing.assert_array_equal(stratified_validation_seeds(gym.make(TRACKING_ID), 5), validation_seeds(5))
    with pytest.raises(ValueError, match="n"):
        stratified_validation_seeds(_Kinds(), 0)


@pytest.mark.parametrize("env_id", ["rdmp_gym/ArmarWipe-v3", "rdmp_gym/PandaWipe-v3"])
def test_the_wiping_validation_holds_every_kind_of_context_evenly(env_id):
    env = gym.make(env_id)
    # the first 50 seeds of the pool hold the first two of every kind (the last of them the 44th), so the choice is
    # the default pool's (400), at an eighth of the resets
    seeds = stratified_validation_seeds(env, 8, pool=50)
    kind_of = contract_of(env).context_kind
    kinds = Counter(kind_of(env.reset(seed=int(s))[0]) for s in seeds)
    assert kinds == dict.fromkeys(CONTEXT_KINDS, 2)
    plain = Counter(kind_of(env.reset(seed=int(s))[0]) for s in validation_seeds(8))
    assert plain["cup on the approach"] < 2                                  # what the plain choice misses


def test_the_setting_is_saved_and_leaves_earlier_runs_keys_alone():
    config = TrainConfig(agent="cmaes", stratified_validation=True)
    assert TrainConfig.from_dict(config.to_dict()) == config
    seeds = final_test_seeds(2)
    plain = TrainConfig(agent="cmaes")
    assert "stratified_validation" not in _cache_key(plain, seeds)        # the key of a run made before it existed
    assert _cache_key(config, seeds) != _cache_key(plain, seeds)
