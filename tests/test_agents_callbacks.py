"""Callbacks of the training loop: hook points and order, a user callback that stops early (and the run resumes
to the uninterrupted numbers), one that replaces a default, the end hook after an error."""

import json
import os

os.environ.setdefault("OMP_NUM_THREADS", "1")

import pytest
from rdmp_gym.agents.callbacks import (
    BestPolicyCallback,
    Callback,
    CallbackList,
    CheckpointCallback,
    EvaluateCallback,
    FirstUpdateGuard,
    LogCallback,
    ProgressBar,
    default_callbacks,
    merge_callbacks,
)
from rdmp_gym.agents.training import TrainConfig, train
from rdmp_gym.envs.registration import TRACKING_ID

pytestmark = pytest.mark.usefixtures("no_learning_curve_figure")      # these tests read no learning curve


def _config(updates=4, **changes):
    values = {"agent": "pi2", "updates": updates, "rollouts": 4, "seed": 1, "env_id": TRACKING_ID,
              "env_kwargs": {"n_periodic": 8, "n_transient": 8, "duration": 3.0}, "start": "perturbed",
              "options": {"sigma": 0.1}}
    values.update(changes)
    return TrainConfig(**values)


def _log(run):
    return [{k: v for k, v in record.items() if k != "time_s"} for record in run.read_log()]


class Recorder(Callback):
    """Records each hook with what it saw."""

    def __init__(self):
        self.calls = []

    def on_training_start(self, state):
        self.calls.append(("start", state.update))

    def on_update(self, state):
        evaluated = None if state.evaluation is None else state.evaluation.summary["eval_return_mean"]
        self.calls.append(("update", state.update, state.batch is None, evaluated, state.record.get("time_s")))

    def on_training_end(self, state):
        self.calls.append(("end", state.update, state.stopped))


class StopAfter(Callback):
    def __init__(self, update):
        self.update = update

    def on_update(self, state):
        return state.update < self.update


def test_a_user_callback_sees_every_hook_after_the_defaults(tmp_path):
    recorder = Recorder()
    run = train(_config(updates=3, eval_every=2), tmp_path / "run", callbacks=[recorder])
    assert recorder.calls[0] == ("start", 0) and recorder.calls[-1] == ("end", 3, False)
    updates = recorder.calls[1:-1]
    assert [call[1] for call in updates] == [0, 1, 2, 3]
    assert [call[2] for call in updates] == [True, False, False, False]          # the start has no batch
    logged = run.read_log()
    assert [call[3] is not None for call in updates] == [True, False, True, True]   # every 2 updates and the last
    assert [call[3] for call in updates if call[3] is not None] == \
        [record["eval_return_mean"] for record in logged if "eval_return_mean" in record]
    assert [call[4] for call in updates] == [record["time_s"] for record in logged]  # after the log callback


def test_a_callback_that_stops_early_leaves_a_run_that_resumes_to_the_uninterrupted_numbers(tmp_path):
    straight = train(_config(), tmp_path / "straight")
    recorder = Recorder()
    stopped = train(_config(), tmp_path / "stopped", callbacks=[StopAfter(2), recorder])
    assert [record["update"] for record in stopped.read_log()] == [0, 1, 2]
    assert stopped.load_checkpoint()["update"] == 2 and recorder.calls[-1] == ("end", 2, True)
    resumed = train(None, tmp_path / "stopped", resume=True)
    assert _log(resumed) == _log(straight)
    assert json.loads(resumed.best_json.read_text()) == json.loads(straight.best_json.read_text())
    assert (resumed.path / "dmp.json").read_bytes() == (straight.path / "dmp.json").read_bytes()


def test_a_callback_of_a_defaults_class_takes_its_place(tmp_path):
    class TaggedLog(LogCallback):
        def on_update(self, state):
            state.record["tag"] = state.update * 10
            super().on_update(state)

    class EvaluateAtTheEnd(EvaluateCallback):
        def due(self, state):
            return state.update >= state.config.updates

    run = train(_config(updates=3), tmp_path / "run", callbacks=[EvaluateAtTheEnd(), TaggedLog()])
    records = run.read_log()
    assert [record["tag"] for record in records] == [0, 10, 20, 30]            # one line per update: replaced
    assert ["eval_return_mean" in record for record in records] == [False, False, False, True]
    assert json.loads(run.best_json.read_text())["update"] == 3


def test_merge_keeps_the_default_order_and_appends_the_rest():
    recorder, log = Recorder(), LogCallback()
    merged = merge_callbacks(default_callbacks(), [recorder, log])
    kinds = [type(callback) for callback in merged.callbacks]
    assert kinds == [EvaluateCallback, BestPolicyCallback, LogCallback, CheckpointCallback, FirstUpdateGuard,
                     ProgressBar, Recorder]
    assert merged.callbacks[2] is log
    with pytest.raises(TypeError, match="Callback"):
        CallbackList([object()])


def test_the_end_hook_runs_when_a_callback_raises(tmp_path):
    class Fail(Callback):
        def on_update(self, state):
            if state.update == 2:
                raise RuntimeError("stop here")

    recorder = Recorder()
    with pytest.raises(RuntimeError, match="stop here"):
        train(_config(), tmp_path / "run", callbacks=[Fail(), recorder])
    assert recorder.calls[-1] == ("end", 2, False)
