"""Smooth actions for PPO and SAC (``length`` > 0): the policy acts on a latent vector that a fixed smooth map
turns into the action, so exploring does not make the paths jagged; everything the agents report is actions."""

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

from rdmp_gym.agents import sb3
from rdmp_gym.agents.learners.contextual import action_layout
from rdmp_gym.agents.sb3 import PPOAgent, SACAgent
from rdmp_gym.agents.sb3_smooth_actions import SmoothActions
from rdmp_gym.agents.tasks import WIPE_ID, WIPE_V2_ID, TaskSpec, task_options
from rdmp_gym.agents.training import TrainConfig, train
from rdmp_gym.envs.registration import TRACKING_ID

WEIGHTS = 20                     # periodic weights per degree of freedom
TASK = TaskSpec(TRACKING_ID, {"n_periodic": WEIGHTS, "n_transient": 10, "duration": 4.0})
N = TASK.make().action_space.shape[0]
OBSERVATIONS = np.zeros((3, TASK.make().observation_space.shape[0]))


def _agent(agent: str, length: float, rollouts: int = 32, initial: np.ndarray | None = None):
    start = np.zeros(N) if initial is None else initial
    options = {"length": length, **({"n_epochs": 1} if agent == "ppo" else {"batch_size": 8})}
    if agent == "ppo":
        return PPOAgent(TASK, start, rollouts=rollouts, workers=1, seed=0, options=options)
    return SACAgent(TASK, start, rollouts=rollouts, seed=0, options=options)


def _roughness(block: np.ndarray) -> float:
    """Mean squared circular second difference of the rows of ``block [K, WEIGHTS]`` per unit mean square."""
    second = np.roll(block, -1, axis=1) - 2 * block + np.roll(block, 1, axis=1)
    return float(np.mean(second**2) / np.mean(block**2))


def _first_batch(agent: str, length: float):
    learner = _agent(agent, length)
    try:
        return learner.train_update()
    finally:
        learner.close()


@pytest.mark.parametrize("agent", ["ppo", "sac"])
def test_smooth_exploration_is_far_smoother_than_independent_noise_and_as_large(agent):
    rough, smooth = (_first_batch(agent, length).actions for length in (0.0, 5.0))
    rough_noise, smooth_noise = (actions[:, :WEIGHTS] - np.mean(actions[:, :WEIGHTS], axis=0)  # first DoF's weights
                                 for actions in (rough, smooth))
    assert _roughness(rough_noise) > 3.0                   # white noise: about 6 per unit variance
    assert _roughness(smooth_noise) < 0.1 * _roughness(rough_noise)
    assert np.all(np.abs(smooth) <= 1.0)
    assert 0.6 < np.std(smooth[:, :WEIGHTS]) / np.std(rough[:, :WEIGHTS]) < 1.4


def test_the_map_keeps_the_imitation_and_the_scale_of_every_dimension():
    env = TASK.make()
    smooth = SmoothActions.from_env(env, 5.0)
    np.testing.assert_allclose(np.linalg.norm(smooth.matrix, axis=1), 1.0)   # noise sigma on z is sigma on a
    np.testing.assert_array_equal(smooth(np.zeros(N)), np.zeros(N))
    initial = action_layout(env)[0]["initial:0"]
    np.testing.assert_array_equal(smooth.matrix[initial, initial], np.eye(initial.stop - initial.start))
    target = 0.3 * np.sin(2 * np.pi * np.arange(N) / WEIGHTS)
    np.testing.assert_allclose(smooth(smooth.latent(target)), target, atol=1e-12)
    columns = smooth.matrix[:WEIGHTS, :WEIGHTS].T               # A z for z = each unit vector of the block
    assert max(_roughness(column[None]) for column in columns) < 0.1    # any z maps to smooth weights
    with pytest.raises(ValueError, match="matrix"):
        SmoothActions(np.ones((3, 4)))


@pytest.mark.parametrize("agent", ["ppo", "sac"])
def test_length_zero_executes_the_policy_as_before(agent, monkeypatch):
    """``length`` 0 has no map; the latent path with ``A = I`` gives the very same episodes."""
    plain = _first_batch(agent, 0.0)
    monkeypatch.setattr(sb3, "_smooth_actions", lambda task, length: SmoothActions(np.eye(N)))
    identity = _first_batch(agent, 0.0)
    np.testing.assert_array_equal(plain.actions, identity.actions)
    np.testing.assert_array_equal(plain.returns, identity.returns)


@pytest.mark.parametrize("agent", ["ppo", "sac"])
def test_the_policy_starts_at_the_start_action_and_its_checkpoint_reloads_to_the_same_actions(agent):
    start = 0.3 * np.sin(2 * np.pi * np.arange(N) / WEIGHTS)
    learner = _agent(agent, 5.0, rollouts=4, initial=start)
    twin = _agent(agent, 5.0, rollouts=4)
    try:
        np.testing.assert_allclose(learner.policy_actions(OBSERVATIONS), start[None].repeat(3, 0), atol=0.05)
        learner.train_update()
        twin.load_state_dict(learner.state_dict())
        actions = learner.policy_actions(OBSERVATIONS)
        np.testing.assert_array_equal(twin.policy_actions(OBSERVATIONS), actions)
        assert np.all(np.abs(actions) <= 1.0)
    finally:
        learner.close()
        twin.close()


def test_a_smooth_ppo_run_resumes(tmp_path):
    def config(updates):
        return TrainConfig(agent="ppo", updates=updates, rollouts=4, seed=0, env_id=TRACKING_ID,
                           env_kwargs=dict(TASK.env_kwargs), options={"length": 5.0, "n_epochs": 1})

    train(config(1), tmp_path / "run")
    records = train(config(2), tmp_path / "run", resume=True).read_log()
    assert [r["episodes"] for r in records] == [0, 4, 8]
    assert all(np.isfinite(r["return_mean"]) for r in records[1:])


@pytest.mark.parametrize(("agent", "length"), [("ppo", -1.0), ("sac", float("inf")), ("ppo", float("nan"))])
def test_a_bad_length_is_an_error_naming_the_option(agent, length):
    with pytest.raises(ValueError, match=f"{agent}.length"):
        TrainConfig(agent=agent, env_id=TRACKING_ID, options={"length": length})


def test_v2_runs_ppo_and_sac_with_smooth_actions_and_v1_keeps_its_published_settings():
    assert task_options(WIPE_V2_ID, "ppo", {}) == {"length": 5.0, "learning_rate": 3e-3}
    assert task_options(WIPE_V2_ID, "sac", {}) == {"length": 5.0}
    assert task_options(WIPE_V2_ID, "ppo", {"length": 0.0, "learning_rate": 3e-2}) == {"length": 0.0,
                                                                                        "learning_rate": 3e-2}
    assert task_options(WIPE_ID, "ppo", {}) == {} and task_options(WIPE_ID, "sac", {}) == {}
