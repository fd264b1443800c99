"""Agents on the MuJoCo wiping env (a fast configuration): evaluation, learning, PPO, the CLI."""

import json
import os

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import gymnasium as gym
import numpy as np
import pytest
import rdmp_gym.envs  # noqa: F401  (registers rdmp_gym/ArmarWipe-v1)
import torch
from rdmp_gym.agents.cli import main
from rdmp_gym.agents.pool import Evaluator
from rdmp_gym.agents.report import evaluate_run
from rdmp_gym.agents.tasks import WIPE_ID, TaskSpec
from rdmp_gym.agents.training import TrainConfig, train

torch.set_num_threads(1)

# no cup: these tests check the learning machinery on the wiping itself (the cup is bench_agents.py's)
FAST = {"n_periodic": 10, "n_transient": 10, "n_periods": 2, "control_rate": 50, "obstacle": False}


@pytest.fixture(scope="module")
def context():
    """A fixed context (the one the env draws for seed 3), so learning curves are deterministic."""
    env = gym.make(WIPE_ID, disable_env_checker=True, **FAST)
    return env.reset(seed=3)[1]["context"].tolist()


def _config(context, agent="pi2", updates=5, **changes):
    values = {"agent": agent, "updates": updates, "rollouts": 8, "seed": 0, "env_kwargs": FAST,
              "reset_options": {"context": context}, "start": "shrunk", "perturbation": 0.3,
              "options": {"sigma": 0.3}}
    values.update(changes)
    return TrainConfig(**values)


def test_imitation_rollouts_wipe_and_are_repeatable():
    spec = TaskSpec(WIPE_ID, FAST)
    with Evaluator(spec, 1) as evaluator:
        n = evaluator.n_actions
        batch = evaluator.run(np.zeros((3, n)), np.array([0, 1, 0]))
        assert evaluator.env.unwrapped.action_time_weights().shape == (batch.cost_traces.shape[1], n)
    assert batch.valid.all()
    assert [cause == "" for cause in batch.failures] == batch.success.tolist()
    assert all(cause in ("", "coverage", "force") for cause in batch.failures)      # no cup, no collision here
    assert np.all(batch.metrics["coverage"] > 0.6) and np.all(batch.metrics["force_in_band_fraction"] > 0.8)
    assert batch.returns[0] == batch.returns[2]                  # same seed, same context, same episode
    np.testing.assert_allclose(-batch.cost_traces.sum(axis=1), batch.returns, atol=1e-6)


@pytest.fixture(scope="module")
def trained(tmp_path_factory, context):
    """``trained(agent)``: the agent's 5-update run from the shrunk start, trained once per module."""
    runs = {}

    def run_of(agent):
        if agent not in runs:
            runs[agent] = train(_config(context, agent), tmp_path_factory.mktemp("trained") / agent)
        return runs[agent]

    return run_of


# cmaes in the slow set: the default set trains it on the tracking task (test_agents_runs.py's exact resume)
@pytest.mark.parametrize("agent", ["pi2", pytest.param("cmaes", marks=pytest.mark.slow)])
def test_learners_improve_the_wipe_from_a_shrunk_start(trained, agent):
    records = trained(agent).read_log()
    start, best = records[0], max(records[1:], key=lambda r: r["eval_return_mean"])
    assert start["eval_coverage"] < 0.85                         # the shrunk pattern misses dirt
    assert best["eval_return_mean"] > start["eval_return_mean"] + 0.03
    assert best["eval_coverage"] > start["eval_coverage"] + 0.02
    assert all(r["valid"] > 0.5 for r in records[1:])


def test_evaluating_a_trained_checkpoint(trained):
    run = trained("pi2")                  # the run of test_learners_improve_the_wipe_from_a_shrunk_start[pi2]
    for policy in ("best", "last"):
        result = evaluate_run(run.path, 2, policy=policy)
        assert result["trained"]["valid_fraction"] == 1.0 and result["imitation"]["valid_fraction"] == 1.0
        assert 0.0 < result["trained"]["coverage_mean"] <= 1.0
    saved = json.loads((run.path / "evaluation.json").read_text())
    assert saved["policy"] == "last" and len(saved["trained"]["returns"]) == 2
    assert (run.path / "evaluation.png").stat().st_size > 10_000


def test_ppo_trains_on_the_env(tmp_path, context):
    run = train(_config(context, agent="ppo", updates=3, options={"sigma": 0.3, "n_epochs": 4}), tmp_path / "ppo")
    records = run.read_log()
    assert [r["episodes"] for r in records] == [0, 8, 16, 24]
    assert all(np.isfinite(r["return_mean"]) for r in records[1:])
    assert records[0]["exploration"] == pytest.approx(0.3, rel=1e-5)
    result = evaluate_run(run.path, 1, policy="last")
    assert result["trained"]["valid_fraction"] == 1.0


def test_cli_main_fit_evaluate_and_errors(tmp_path, capsys):
    out = tmp_path / "main"
    tiny = ["--updates", "2", "--rollouts", "4", "--workers", "1", "--env-option", "n_periodic", "10",
            "n_transient", "10", "--env-option", "n_periods", "2", "control_rate", "25", "frame_stride", "25", "width",
            "64", "height", "64"]
    assert main(["main", "--out", str(out), "--episodes", "2", "--eval-episodes", "1", "--video", *tiny]) == 0
    assert "trained fails on: " in capsys.readouterr().out
    for name in ("fit.png", "summary.json", "train/log.jsonl", "train/learning_curve.png", "train/evaluation.png",
                 "train/best_episode.mp4", "train/best_params.json"):
        assert (out / name).exists(), name
    assert (out / "train" / "best_episode.mp4").stat().st_size > 0
    summary = json.loads((out / "summary.json").read_text())
    assert set(summary["evaluation"]) == {"imitation", "trained"}
    config = json.loads((out / "train" / "config.json").read_text())        # the main job's own defaults
    assert config["env_kwargs"]["cup_clearance"] == 0.01 and config["options"]["sigma_factors"] == {"approach": 3.0}
    assert main(["fit", "--style", "3", "--plot", "--out", str(tmp_path / "fit")]) == 0
    assert (tmp_path / "fit" / "fit.png").exists() and (tmp_path / "fit" / "dmp.json").exists()
    assert main(["evaluate", str(out / "train"), "--episodes", "1", "--workers", "1"]) == 0
    capsys.readouterr()
    assert main(["train", "--out", str(tmp_path / "bad"), "--options.sigmaa", "0.2"]) == 2     # tyro names it
    assert main(["train", "--out", str(tmp_path / "bad"), "--env-option", "n_periodics", "3"]) == 2
    assert "n_periodics" in capsys.readouterr().err
    assert main(["train", "--out", str(out / "train"), "--resume", "--seed", "4"]) == 2
    assert "seed" in capsys.readouterr().err                     # a resumed run keeps its configuration


@pytest.mark.slow
def test_cli_train_films_the_best_episode_and_resumes(tmp_path):
    """``train --video`` and ``--resume`` from the command line on this env (the default set checks the video of
    ``main``'s training and the CLI's resume on the tracking env, ``test_cli_every_env.py``)."""
    tiny = ["--updates", "2", "--rollouts", "4", "--workers", "1", "--env-option", "n_periodic", "10",
            "n_transient", "10", "--env-option", "n_periods", "2", "control_rate", "25", "frame_stride", "25", "width",
            "64", "height", "64"]
    assert main(["train", "--agent", "cmaes", "--out", str(tmp_path / "cmaes"), "--video", *tiny]) == 0
    assert (tmp_path / "cmaes" / "best_episode.mp4").stat().st_size > 0
    assert main(["train", "--agent", "cmaes", "--out", str(tmp_path / "cmaes"), "--resume", "--updates", "3",
                 *tiny[2:]]) == 0
    assert len((tmp_path / "cmaes" / "log.jsonl").read_text().splitlines()) == 4


def test_ppo_reports_a_diverged_policy_clearly(context):
    from rdmp_gym.agents.sb3 import PPOAgent

    spec = TaskSpec(WIPE_ID, FAST, {"context": context})
    n = gym.make(WIPE_ID, disable_env_checker=True, **FAST).action_space.shape[0]
    agent = PPOAgent(spec, np.zeros(n), rollouts=2, workers=1, seed=0, options={"n_epochs": 1})
    try:
        with torch.no_grad():
            agent.model.policy.log_std.fill_(float("nan"))
        with pytest.raises(FloatingPointError, match="diverged"):
            agent.train_update()
    finally:
        agent.close()


def test_contextual_learners_explore_the_approach_dimension():
    """ArmarWipe-v1's ``approach`` (the last action dimension, outside the DMP's parameter groups) is searched
    and can depend on the context: without it no learner could learn to lift over the cup."""
    from rdmp_gym.agents.learners import SearchSpace, make_learner

    env = gym.make(WIPE_ID)
    observations = np.stack([env.reset(seed=s)[0] for s in range(8)]).astype(np.float64)
    space = SearchSpace.from_env(env, observations)
    n = env.action_space.shape[0]
    assert space.slices["approach"] == slice(n - 1, n)
    assert space.context_names[10:13] == ("obstacle", "obstacle_position", "obstacle_position")
    learner = make_learner("cpi2", np.zeros(n), 4, np.random.default_rng(0),
                           {"gain_groups": "amplitude,approach", "features": "patch_size,obstacle"}, space=space)
    actions = learner.ask(observations[:4])
    assert np.std(actions[:, -1]) > 0.05
    env.close()
