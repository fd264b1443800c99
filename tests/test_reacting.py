"""The reacting learner: an open-loop stage, then each cycle's change of its policy on the cycle-level face."""

import gymnasium as gym
import numpy as np
import pytest
from rdmp_gym.agents.cycle_training import cycle_episode, linear_actor, train_cycle_search
from rdmp_gym.agents.reacting import open_loop_curve, train_reacting

ENV = "rdmp_gym/PandaWipe-v3"


def _zero_policy(env) -> dict[str, np.ndarray]:
    size, n = env.observation_space.shape[0], env.action_space.shape[0]
    return {"maps": np.zeros((env.n_cycles, n, size + 1)), "center": np.zeros(size), "scale": np.zeros(size),
            "active": np.ones((env.n_cycles, n), dtype=bool)}


def test_a_base_action_in_every_cycle_is_the_episodic_face_s_action():
    env = gym.make("rdmp_gym/PandaWipeCycle-v3").unwrapped
    action = np.random.default_rng(1).normal(0.0, 0.05, env.action_space.shape[0])
    result = cycle_episode(env, linear_actor(_zero_policy(env), np.repeat(action[None], env.n_cycles, 0)), seed=4)
    episodic = gym.make(ENV)
    episodic.reset(seed=4)
    reward = episodic.step(action)[1]
    assert np.all(result["actions"] == action)
    assert result["return"] == pytest.approx(reward, abs=1e-9) and result["refused"] == 0
    env.close()
    episodic.close()


def test_the_base_policy_is_evaluated_first_and_its_shape_is_checked():
    seen = []

    def wrong_size(contexts):
        seen.append(contexts.shape)
        return np.zeros((len(contexts), 1))

    run = train_cycle_search(ENV, episodes=4, rollouts=2, seed=0, workers=1, eval_every=1, validation=1, test=1,
                             validation_pool=1, base=lambda contexts: np.zeros((len(contexts), _n_actions())))
    assert run.curve[0]["episodes"] == 0 and [row["episodes"] for row in run.curve[1:]] == [4]
    with pytest.raises(ValueError, match="base: expected finite actions"):
        train_cycle_search(ENV, episodes=4, rollouts=2, seed=0, workers=1, validation=1, test=1, validation_pool=1,
                           base=wrong_size)
    assert seen and seen[0][0] == 2


def _n_actions() -> int:
    return gym.make("rdmp_gym/PandaWipeCycle-v3").action_space.shape[0]


@pytest.mark.parametrize(("episodes", "open_loop", "match"), [(100, 0.0, "open_loop"), (100, 1.0, "open_loop"),
                                                              (40, 0.5, "episodes")])
def test_bad_budgets_are_refused_before_any_training(tmp_path, episodes, open_loop, match):
    with pytest.raises(ValueError, match=match):
        train_reacting(ENV, tmp_path, episodes=episodes, open_loop=open_loop)
    assert not any(tmp_path.iterdir())


def test_the_open_loop_log_becomes_curve_rows():
    log = [{"update": 0, "episodes": 0, "eval_success": 0.1, "eval_return_mean": 0.9},
           {"update": 1, "episodes": 20, "eval_success": None, "eval_return_mean": None},
           {"update": 2, "episodes": 40, "eval_success": 0.5, "eval_return_mean": 1.0}]
    rows = open_loop_curve(log)
    assert [row["episodes"] for row in rows] == [0, 40]
    assert rows[1]["validation_success"] == 0.5 and rows[1]["validation_return"] == 1.0


@pytest.mark.slow
def test_train_reacting_end_to_end(tmp_path):
    run = train_reacting(ENV, tmp_path, episodes=100, open_loop=0.4, workers=1, validation=2, test=2)
    stages = [row.get("stage") for row in run.curve]
    assert stages[:2] == ["open loop", "open loop"] and run.curve[2]["episodes"] == 40
    assert run.config["open_loop"]["episodes"] == 40 and len(run.test["success"]) == 2
    assert (tmp_path / "open_loop" / "config.json").exists()
