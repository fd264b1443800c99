"""The step-twin benchmark (``benchmarks/bench_step_twin.py``): its episode length and its summary over seeds."""

import gymnasium as gym
import pytest
import rdmp_gym.envs  # noqa: F401
from bench_step_twin import episode_steps, summary


def test_episode_steps_of_a_step_twin_are_its_episodic_faces():
    env = gym.make("rdmp_gym/PandaDrumStep-v1")
    assert episode_steps(env) == gym.make("rdmp_gym/PandaDrum-v1").unwrapped.n_steps == 1000
    with pytest.raises(ValueError, match="env_id"):
        episode_steps(gym.make("Pendulum-v1", max_episode_steps=None).unwrapped)


def _run(agent, seed, successes, causes):
    return {"agent": agent, "seed": seed, "env_steps": 150_000, "seconds": 1.0,
            "test": {"success": successes, "return": [1.0] * len(successes), "causes": causes}}


def test_summary_gives_each_agent_its_iqm_interval_and_causes():
    runs = [_run("ppo", 0, [True, False], [[], ["timing"]]), _run("ppo", 1, [True, True], [[], []]),
            _run("sac", 0, [False, False], [["jerk", "timing"], ["timing"]])]
    rows = {row["agent"]: row for row in summary(runs)}
    assert rows["ppo"]["seeds"] == 2 and rows["sac"]["seeds"] == 1
    assert rows["ppo"]["success"]["low"] == 0.5 and rows["ppo"]["success"]["high"] == 1.0
    assert rows["sac"]["success"]["estimate"] == 0.0
    assert rows["sac"]["causes"] == {"timing": 2, "jerk": 1}
