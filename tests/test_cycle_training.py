"""Training on the cycle-level face end to end: the cycle-by-cycle search, SAC, and the rdmp-gym cycles command."""

import json

import numpy as np
import pytest
from rdmp_gym.agents.cli import main as cli_main
from rdmp_gym.agents.cycle_training import CycleRun, cycle_episode, linear_actor, summarise, train_cycle_search

ENV = "rdmp_gym/PandaWipe-v3"


@pytest.fixture(scope="module")
def tiny_runs() -> list[CycleRun]:
    """Two runs of the same seed: the imitation batch, one update, validation and test on one context each."""
    return [train_cycle_search(ENV, episodes=4, rollouts=2, seed=5, workers=1, eval_every=1, validation=1, test=1,
                               validation_pool=1)
            for _ in range(2)]


def test_a_run_is_reproducible_and_reports_the_test_contexts(tiny_runs):
    first, second = tiny_runs
    assert first.curve == second.curve and first.test == second.test
    assert first.env_id == "rdmp_gym/PandaWipeCycle-v3" and first.curve[0]["episodes"] == 4
    assert first.test["seeds"] == [2**30] and len(first.test["success"]) == 1
    assert np.isfinite(first.test["jerk_ratio"][0]) and first.test["jerk_ratio"][0] > 0
    table = summarise(tiny_runs)
    assert table["runs"] == 2 and 0.0 <= table["test_success"]["estimate"] <= 1.0


def test_the_zero_policy_is_the_imitation_in_every_cycle(tiny_runs):
    import gymnasium as gym

    env = gym.make("rdmp_gym/PandaWipeCycle-v3").unwrapped
    size = env.observation_space.shape[0]
    zero = {"maps": np.zeros((env.n_cycles, env.action_space.shape[0], size + 1)), "center": np.zeros(size),
            "scale": np.zeros(size), "active": np.ones((env.n_cycles, env.action_space.shape[0]), dtype=bool)}
    result = cycle_episode(env, linear_actor(zero), seed=3)
    episodic = gym.make(ENV)
    episodic.reset(seed=3)
    reward = episodic.step(np.zeros(episodic.action_space.shape))[1]
    assert result["return"] == reward and result["jerk_ratio"] == pytest.approx(1.0)
    assert np.all(result["actions"] == 0) and result["spent"][0] == 0.0
    assert np.all(np.diff(result["spent"]) != 0)
    env.close()


@pytest.mark.parametrize("algorithm", ["sac", "ppo"])
def test_sb3_on_the_cycle_face_starts_at_the_imitation_with_the_given_exploration(algorithm):
    import gymnasium as gym
    from rdmp_gym.agents.cycle_sb3 import _model

    env = gym.make("rdmp_gym/PandaWipeCycle-v3")
    model = _model(algorithm, env, seed=0, sigma=0.3, episode_steps=7, rollouts=2)
    observation = env.observation_space.sample()
    assert np.abs(model.predict(observation, deterministic=True)[0]).max() < 0.01
    draws = np.stack([model.predict(observation, deterministic=False)[0] for _ in range(200)])
    assert 0.25 < draws.std() < 0.32                 # SAC squashes its N(0, 0.3): a standard deviation near 0.29
    env.close()


@pytest.mark.slow
def test_sac_on_the_cycle_face_runs_and_keeps_the_best_policy():
    from rdmp_gym.agents.cycle_sb3 import train_cycle_sb3

    run = train_cycle_sb3(ENV, "sac", episodes=2, seed=0, eval_every=1, validation=1, test=1, validation_pool=1)
    assert [row["episodes"] for row in run.curve] == [1, 2]
    assert run.best_episodes in (1, 2) and len(run.test["success"]) == 1
    with pytest.raises(ValueError, match="algorithm"):
        train_cycle_sb3(ENV, "a2c", episodes=2)


def test_the_cycles_command_writes_its_run(tmp_path, capsys):
    out = tmp_path / "run"
    assert cli_main(["cycles", "--env", ENV, "--episodes", "4", "--rollouts", "2", "--workers", "1",
                     "--validation", "1", "--validation-pool", "1", "--test", "1", "--out", str(out)]) == 0
    run = json.loads((out / "run.json").read_text())
    assert run["env_id"] == "rdmp_gym/PandaWipeCycle-v3" and (out / "curve.png").stat().st_size > 0
    assert "test success" in capsys.readouterr().out
    assert cli_main(["cycles", "--env", ENV, "--episodes", "3", "--rollouts", "2", "--out", str(out)]) == 2
