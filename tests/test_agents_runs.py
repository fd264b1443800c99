"""Training runs on the MuJoCo-free DMP task: run directory, exact resume, parallel = serial, bad configs."""

import json
import os

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np
import pytest
from rdmp_gym.agents.pool import Evaluator
from rdmp_gym.agents.tasks import TaskSpec
from rdmp_gym.agents.training import TrainConfig, train
from rdmp_gym.envs.registration import TRACKING_ID

LOG_KEYS = {"update", "episodes", "eval_episodes", "exploration", "eval_return_mean", "eval_return_best",
            "eval_success", "eval_rms_error", "eval_valid", "best_eval_return", "time_s"}

# train without drawing learning_curve.png, for the tests that read no figure (the run directory test reads it)
NO_CURVE = pytest.mark.usefixtures("no_learning_curve_figure")


def _config(agent="pi2", updates=3, **changes):
    values = {"agent": agent, "updates": updates, "rollouts": 6, "seed": 3, "env_id": TRACKING_ID,
              "env_kwargs": {"n_periodic": 10, "n_transient": 10, "duration": 4.0}, "start": "perturbed",
              "options": {"sigma": 0.1}}
    values.update(changes)
    return TrainConfig(**values)


def _without_time(records):
    return [{k: v for k, v in r.items() if k != "time_s"} for r in records]


def test_run_directory_holds_config_log_checkpoint_best_and_curve(tmp_path):
    run = train(_config(), tmp_path / "run")
    names = {p.name for p in run.path.iterdir()}
    assert {"config.json", "provenance.json", "log.jsonl", "checkpoint.json", "best_params.npy", "best_params.json",
            "learning_curve.png"} <= names
    records = run.read_log()
    assert [r["update"] for r in records] == [0, 1, 2, 3]
    assert [r["episodes"] for r in records] == [0, 6, 12, 18]
    assert LOG_KEYS <= set(records[0])
    assert {"return_mean", "return_best", "rms_error", "success"} <= set(records[1])  # the task's metric by its key
    assert records[1]["exploration"] < records[0]["exploration"]          # PI² anneals
    assert records[0]["eval_success"] is None and records[1]["success"] is None     # the task reports no success
    assert not any("coverage" in key for record in records for key in record)      # no other task's metric
    best = json.loads(run.best_json.read_text())
    assert best["eval_return_mean"] == max(r["eval_return_mean"] for r in records)
    np.testing.assert_allclose(np.load(run.best_npy), best["action"])
    assert TrainConfig.from_dict(run.read_config()) == _config()


@NO_CURVE
@pytest.mark.parametrize("agent", ["pi2", "cmaes"])
def test_resume_gives_exactly_the_uninterrupted_run(tmp_path, agent):
    straight = train(_config(agent, updates=4), tmp_path / "straight")
    train(_config(agent, updates=2), tmp_path / "killed")
    resumed = train(_config(agent, updates=4), tmp_path / "killed", resume=True)
    assert _without_time(resumed.read_log()) == _without_time(straight.read_log())
    a, b = straight.load_checkpoint()["agent"], resumed.load_checkpoint()["agent"]
    np.testing.assert_array_equal(a["learner"]["mean"], b["learner"]["mean"])
    assert a["episode_rng"] == b["episode_rng"]
    np.testing.assert_array_equal(straight.load_best(), resumed.load_best())


@NO_CURVE
def test_resume_after_a_kill_between_log_and_checkpoint_redoes_the_update(tmp_path):
    straight = train(_config(updates=3), tmp_path / "straight")
    run = train(_config(updates=2), tmp_path / "killed")
    with run.log_path.open("a") as handle:     # the log got update 3, the checkpoint did not
        handle.write(json.dumps({"update": 3, "episodes": 18, "half": True}) + "\n")
    resumed = train(None, tmp_path / "killed", resume=True)
    assert len(resumed.read_log()) == 3      # config.json says 2 updates: nothing to redo
    resumed = train(_config(updates=3), tmp_path / "killed", resume=True)
    assert _without_time(resumed.read_log()) == _without_time(straight.read_log())


@NO_CURVE
def test_a_new_run_never_overwrites_and_resume_checks_the_config(tmp_path):
    train(_config(updates=1), tmp_path / "run")
    with pytest.raises(FileExistsError, match="resume"):
        train(_config(updates=1), tmp_path / "run")
    with pytest.raises(ValueError, match="seed"):
        train(_config(updates=2, seed=4), tmp_path / "run", resume=True)
    with pytest.raises(FileNotFoundError, match=r"config.json"):
        train(None, tmp_path / "nothing", resume=True)


def test_parallel_evaluation_gives_the_serial_numbers():
    spec = TaskSpec(TRACKING_ID, {"n_periodic": 10, "n_transient": 10, "context_range": 0.02})
    actions = np.random.default_rng(0).uniform(-0.3, 0.3, (5, 62))
    seeds = np.arange(5)
    with Evaluator(spec, 1) as serial, Evaluator(spec, 2) as parallel:
        a, b = serial.run(actions, seeds), parallel.run(actions, seeds)
    np.testing.assert_array_equal(a.returns, b.returns)
    np.testing.assert_array_equal(a.cost_traces, b.cost_traces)
    assert len(set(a.returns.tolist())) == 5          # different contexts and actions


@NO_CURVE
def test_bad_configs_fail_clearly(tmp_path):
    with pytest.raises(ValueError, match="agent"):
        _config(agent="td3")
    with pytest.raises(ValueError, match="sigmaa"):
        _config(options={"sigmaa": 0.1})
    with pytest.raises(ValueError, match="ppo"):
        _config(agent="ppo", options={"decay": 0.9})
    with pytest.raises(ValueError, match="rollouts"):
        _config(rollouts=1)
    with pytest.raises(ValueError, match="start"):
        _config(start="random")
    with pytest.raises(ValueError, match="updatez"):
        TrainConfig.from_dict({"updatez": 3})
    with pytest.raises(TypeError, match=r"config.updates"):
        TrainConfig.from_dict({"updates": "3"})
    with pytest.raises(TypeError, match="n_periodics"):
        train(_config(env_kwargs={"n_periodics": 3}), tmp_path / "bad")
    with pytest.raises(ValueError, match="actions"):
        with Evaluator(TaskSpec(TRACKING_ID), 1) as evaluator:
            evaluator.run(np.zeros((2, 3)), np.arange(2))
    assert not (tmp_path / "bad").exists()          # nothing written for a run that cannot start


@NO_CURVE
def test_a_user_demonstration_file_is_the_imitation_start(tmp_path):
    from rdmp_gym import wiping_demonstration

    path = tmp_path / "demo.csv"
    wiping_demonstration(3, rng=1).to_csv(path)
    config = _config(updates=1, demo=str(path), start="imitation",
                     env_kwargs={"n_periodic": 10, "n_transient": 10, "duration": 4.0, "shift": [0.0, 0.0, 0.0]})
    env = config.task.make()
    assert env.unwrapped.demo.name == "demo"            # the env fitted the file, not its built-in style
    run = train(config, tmp_path / "run")
    assert run.read_log()[0]["eval_return_mean"] > -0.1    # a = 0 reproduces the demonstration (unshifted)
    with pytest.raises(FileNotFoundError, match="demo"):
        _config(demo=str(tmp_path / "missing.npz")).task.make()
