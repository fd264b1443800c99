"""Execution backends: Ray = local pool, workers exit with their parent, a dead worker is a clear error,
PPO's numbers do not depend on the worker count."""

import os

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import rdmp_gym.envs  # noqa: F401  (registers rdmp_gym/ArmarWipe-v1)
from rdmp_gym.agents.pool import Evaluator, WorkerError
from rdmp_gym.agents.runs import RunDirectory
from rdmp_gym.agents.tasks import WIPE_ID, TaskSpec
from rdmp_gym.agents.training import TrainConfig, train
from rdmp_gym.envs.registration import TRACKING_ID

FAST = {"n_periodic": 10, "n_transient": 10, "n_periods": 2, "control_rate": 50}
TRACKING = {"n_periodic": 10, "n_transient": 10, "duration": 4.0}
pytestmark = pytest.mark.usefixtures("no_learning_curve_figure")      # these tests read no learning curve


def _without_time(records):
    return [{k: v for k, v in r.items() if k != "time_s"} for r in records]


@pytest.mark.slow          # starts a Ray cluster (~25 s); the default set checks the backend's errors
def test_ray_backend_gives_the_numbers_of_the_local_pool(tmp_path):
    ray = pytest.importorskip("ray")
    context = gym.make(WIPE_ID, disable_env_checker=True, **FAST).reset(seed=3)[1]["context"]
    config = TrainConfig(agent="pi2", env_id=WIPE_ID, updates=2, rollouts=4, seed=1, workers=2, env_kwargs=FAST,
                         reset_options={"context": context.tolist()}, start="perturbed", options={"sigma": 0.3},
                         eval_episodes=2)
    local = train(config, tmp_path / "local")
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:                          # the same run on 2 Ray actors
        train(config, tmp_path / "ray", backend="ray")
        status = 0
    finally:
        ray.shutdown()
    assert status == 0
    distributed = RunDirectory(tmp_path / "ray")
    records = _without_time(local.read_log())
    assert [r["update"] for r in records] == [0, 1, 2]
    assert _without_time(distributed.read_log()) == records
    np.testing.assert_array_equal(local.load_best(), distributed.load_best())
    assert len({r["return_mean"] for r in records[1:]}) == 2      # the updates differ: a real search ran


def test_the_ray_backend_without_ray_says_how_to_install_it(monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)                # makes "import ray" fail
    with pytest.raises(ImportError, match=r"rdmp-gym\[ray\]"):
        Evaluator(TaskSpec(TRACKING_ID, TRACKING), 1, backend="ray")


def test_a_bad_backend_is_refused():
    with pytest.raises(ValueError, match="backend"):
        Evaluator(TaskSpec(TRACKING_ID, TRACKING), 1, backend="dask")
    with pytest.raises(ValueError, match="ray_address"):
        Evaluator(TaskSpec(TRACKING_ID, TRACKING), 1, ray_address="auto")


def _children(pid: int) -> set[int]:
    """Every descendant process of ``pid`` (Linux /proc)."""
    found, stack = set(), [pid]
    while stack:
        parent = stack.pop()
        for task in Path(f"/proc/{parent}/task").glob("*"):
            try:
                kids = {int(k) for k in (task / "children").read_text().split()}
            except (OSError, ValueError):
                continue
            stack.extend(kids - found)
            found |= kids
    return found


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


@pytest.mark.slow          # a CLI run in its own interpreter; the default set checks a dead worker's error
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_workers_exit_when_a_training_run_is_killed(tmp_path):
    command = [sys.executable, "-m", "rdmp_gym.agents.cli", "train", "--out", str(tmp_path / "run"),
               "--env", TRACKING_ID, "--env-option", "n_periodic", "10", "n_transient", "10", "duration", "4",
               "--updates", "1000", "--rollouts", "4", "--workers", "2"]
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 60
        while not (tmp_path / "run" / "log.jsonl").exists():     # the workers have run episodes
            assert process.poll() is None and time.monotonic() < deadline, "the run did not start"
            time.sleep(0.2)
        children = _children(process.pid)
        assert len(children) >= 2
        process.send_signal(signal.SIGKILL)
        process.wait()
        deadline = time.monotonic() + 10
        while any(_alive(pid) for pid in children) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not [pid for pid in children if _alive(pid)]
    finally:
        process.kill()


def test_a_dead_worker_is_a_clear_error():
    spec = TaskSpec(TRACKING_ID, TRACKING)
    with Evaluator(spec, 2) as evaluator:
        actions = np.zeros((4, evaluator.n_actions))
        evaluator.run(actions, np.arange(4))
        victim = next(iter(evaluator._pool._executor._processes.values()))
        victim.kill()
        victim.join()
        with pytest.raises(WorkerError, match="--resume"):
            evaluator.run(actions, np.arange(4))


@pytest.mark.slow          # two PPO agents; the default set checks the parallel evaluation against the serial one
def test_ppo_numbers_do_not_depend_on_the_worker_count():
    pytest.importorskip("stable_baselines3")
    from rdmp_gym.agents.sb3 import PPOAgent

    spec = TaskSpec(TRACKING_ID, TRACKING)
    batches = []
    for workers in (1, 2):
        agent = PPOAgent(spec, np.zeros(62), rollouts=4, workers=workers, seed=2, options={"n_epochs": 2, "envs": 2})
        try:
            batches.append([agent.train_update(), agent.train_update()])
        finally:
            agent.close()
    for serial, parallel in zip(*batches, strict=True):
        np.testing.assert_array_equal(serial.actions, parallel.actions)
        np.testing.assert_array_equal(serial.returns, parallel.returns)
    assert not np.array_equal(batches[0][0].actions, batches[0][1].actions)     # the policy or its samples moved


def test_a_run_stopped_by_a_dead_worker_resumes_to_the_uninterrupted_numbers(tmp_path, monkeypatch):
    config = TrainConfig(agent="pi2", updates=3, rollouts=4, seed=5, env_id=TRACKING_ID, env_kwargs=TRACKING,
                         start="perturbed", options={"sigma": 0.1})
    whole = train(config, tmp_path / "whole")
    calls = {"count": 0}
    run_batch = Evaluator.run

    def dying(self, actions, seeds):
        calls["count"] += 1
        if calls["count"] == 4:            # the training episodes of the second update
            raise WorkerError("evaluation: a worker process died")
        return run_batch(self, actions, seeds)

    monkeypatch.setattr(Evaluator, "run", dying)
    with pytest.raises(WorkerError):
        train(config, tmp_path / "broken")
    monkeypatch.setattr(Evaluator, "run", run_batch)
    resumed = train(None, tmp_path / "broken", resume=True)
    assert _without_time(resumed.read_log()) == _without_time(whole.read_log())


@pytest.mark.slow
def test_bench_agents_on_ray_writes_the_result_file_of_the_local_run(tmp_path):
    pytest.importorskip("ray")
    script = Path(__file__).resolve().parent.parent / "benchmarks" / "bench_agents.py"
    documents = {}
    for backend in ("local", "ray"):
        subprocess.run([sys.executable, str(script), "--agents", "creps", "--seeds", "2", "--budget", "10",
                        "--rollouts", "5", "--test-contexts", "2", "--val-contexts", "1", "--eval-every", "1",
                        "--backend", backend, "--name", f"check_{backend}"], check=True, cwd=tmp_path,
                       env={**os.environ, "PYTHONPATH": str(script.parent)}, capture_output=True)
        path = script.parent.parent / "runs" / "benchmarks" / f"check_{backend}.json"
        documents[backend] = json.loads(path.read_text())
        path.unlink()
        path.with_suffix(".png").unlink()
    runs = {b: [{k: v for k, v in r.items() if k != "seconds"} for r in d["runs"]] for b, d in documents.items()}
    assert len(runs["local"]) == 2 and runs["ray"] == runs["local"]
    assert documents["ray"]["summary"] == documents["local"]["summary"]
    assert runs["local"][0]["curve"] != runs["local"][1]["curve"]          # two seeds, two real runs
    for run in runs["ray"]:                                                # each test context says why it failed
        assert [cause == "" for cause in run["test"]["failures"]] == run["test"]["success"]
