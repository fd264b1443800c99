"""Runs and files you can trust (issue 11): no code in checkpoints, no silent mixing, no silent NaN.

The numbered comments refer to the items of the issue. Runs use the MuJoCo-free tracking task, except
for the all-invalid run (item 6), which needs the wiping env's validity check.
"""

import json
import os
import pickle

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import filelock
import numpy as np
import pytest
from rdmp_gym.agents import runs as runs_module
from rdmp_gym.agents.cli import main
from rdmp_gym.agents.pool import Evaluator
from rdmp_gym.agents.report import evaluate_run
from rdmp_gym.agents.runs import RunDirectory, RunLockedError
from rdmp_gym.agents.training import NoValidEpisodesError, TrainConfig, train
from rdmp_gym.envs.registration import TRACKING_ID

ENV = {"n_periodic": 8, "n_transient": 8, "duration": 3.0}
pytestmark = pytest.mark.usefixtures("no_learning_curve_figure")      # these tests read no learning curve


def _config(agent="pi2", updates=2, **changes):
    values = {"agent": agent, "updates": updates, "rollouts": 4, "seed": 3, "env_id": TRACKING_ID,
              "env_kwargs": ENV, "start": "perturbed", "options": {"sigma": 0.1}}
    values.update(changes)
    return TrainConfig(**values)


def _cli_train(out, *flags):
    return main(["train", "--out", str(out), "--env", TRACKING_ID, "--workers", "1", *flags])


def _updates(run):
    return [r["update"] for r in RunDirectory(run).read_log()]


class _Payload:
    """Unpickling this runs a command that leaves a marker file (what a crafted checkpoint could do)."""

    def __init__(self, marker):
        self.marker = str(marker)

    def __reduce__(self):
        return (os.system, (f"touch {self.marker}",))


# 1. A checkpoint cannot run code ----------------------------------------------------------------------
def test_checkpoints_are_json_and_npz_and_an_old_pickle_is_refused_unread(tmp_path):
    run = train(_config(), tmp_path / "run")
    document = json.loads(run.checkpoint_path.read_text())
    npz = run.path / document["files"]["arrays"]
    with np.load(npz, allow_pickle=False) as archive:          # no object arrays inside
        assert all(archive[key].dtype.kind in "biuf" for key in archive.files)
    state = run.load_checkpoint()
    assert state["update"] == 2 and state["agent"]["learner"]["mean"].shape == (50,)
    assert isinstance(state["agent"]["episode_rng"], dict)
    # an old-style pickle checkpoint with a payload: refused by name, never unpickled
    marker = tmp_path / "ran"
    for path in run.path.glob("checkpoint*"):
        path.unlink()
    run.legacy_checkpoint_path.write_bytes(pickle.dumps({"agent": _Payload(marker)}))
    with pytest.raises(ValueError, match=r"checkpoint.pkl.*pickle"):
        train(None, run.path, resume=True)
    with pytest.raises(ValueError, match=r"checkpoint.pkl.*pickle"):
        evaluate_run(run.path, 1, policy="last")
    assert not marker.exists()


def test_an_object_array_in_the_checkpoint_npz_is_refused(tmp_path):
    run = train(_config(updates=1), tmp_path / "run")
    document = json.loads(run.checkpoint_path.read_text())
    npz = run.path / document["files"]["arrays"]
    with np.load(npz) as archive:
        arrays = {key: archive[key] for key in archive.files}
    arrays["a0"] = np.array([_Payload(tmp_path / "ran")], dtype=object)
    with npz.open("wb") as handle:
        np.savez(handle, **arrays)
    document["sha256"][npz.name] = runs_module.sha256_file(npz)       # a consistent, crafted checkpoint
    run.checkpoint_path.write_text(json.dumps(document))
    with pytest.raises(ValueError, match=r"checkpoint-1.npz: unreadable"):
        run.load_checkpoint()
    assert not (tmp_path / "ran").exists()


# 2. --resume reads the run's own config ---------------------------------------------------------------
def test_resume_takes_the_runs_config_and_only_extending_flags(tmp_path, capsys):
    out = tmp_path / "run"
    assert _cli_train(out, "--agent", "cmaes", "--updates", "2", "--rollouts", "4", "--seed", "5",
                      "--env-option", "n_periodic", "8", "n_transient", "8", "--env-option", "duration", "3") == 0
    assert _cli_train(out, "--resume") == 0                   # no flags: the run is complete, nothing added
    assert _updates(out) == [0, 1, 2]
    assert _cli_train(out, "--resume", "--updates", "3", "--seed", "5") == 0  # a repeated equal flag is fine
    assert _updates(out) == [0, 1, 2, 3]
    assert json.loads((out / "config.json").read_text())["updates"] == 3
    capsys.readouterr()
    assert _cli_train(out, "--resume", "--updates", "4", "--env-option", "n_periodic", "9") == 2
    assert "--env-option n_periodic" in capsys.readouterr().err
    assert _cli_train(out, "--resume", "--options.sigma", "0.5") == 2
    assert "--options.sigma" in capsys.readouterr().err
    assert _cli_train(out, "--resume", "--env-option", "weight_scale", "0.4") == 2
    assert "--env-option weight_scale" in capsys.readouterr().err
    assert _cli_train(out, "--resume", "--updates", "2") == 2           # cannot shrink a run
    assert "--updates 3 or more" in capsys.readouterr().err
    assert _updates(out) == [0, 1, 2, 3]


# 3. Two writers, one run ------------------------------------------------------------------------------
def test_a_second_writer_gets_a_clear_error(tmp_path, capsys):
    run = train(_config(updates=1), tmp_path / "run")
    with filelock.FileLock(run.lock_path, timeout=0):          # another process is writing the run
        with pytest.raises(RunLockedError, match="another process"):
            train(_config(updates=2), run.path, resume=True)
        assert _cli_train(run.path, "--resume", "--updates", "2") == 2
        assert "another process" in capsys.readouterr().err
    assert _updates(run.path) == [0, 1]
    train(_config(updates=2), run.path, resume=True)
    assert _updates(run.path) == [0, 1, 2]


# 4. Stale directories are refused ---------------------------------------------------------------------
def test_a_directory_with_files_but_no_config_is_refused_and_left_alone(tmp_path):
    stale = tmp_path / "stale"
    stale.mkdir()
    (stale / "log.jsonl").write_text('{"update": 0}\n')
    np.save(stale / "best_params.npy", np.ones(3))
    with pytest.raises(FileExistsError, match=r"no config\.json"):
        train(_config(), stale)
    assert (stale / "log.jsonl").read_text() == '{"update": 0}\n'
    np.testing.assert_array_equal(np.load(stale / "best_params.npy"), np.ones(3))
    assert sorted(p.name for p in stale.iterdir()) == ["best_params.npy", "log.jsonl"]
    empty = tmp_path / "empty"
    empty.mkdir()
    train(_config(updates=1), empty)                          # an empty directory is fine


# 5. Runs are self-contained ---------------------------------------------------------------------------
def test_the_demo_is_copied_into_the_run_and_versions_are_recorded(tmp_path, monkeypatch):
    from rdmp_gym import wiping_demonstration

    monkeypatch.chdir(tmp_path)
    wiping_demonstration(3, rng=1).to_csv(tmp_path / "demo.csv")
    config = _config(updates=1, demo="demo.csv", env_kwargs={**ENV, "shift": [0.0, 0.0, 0.0]}, start="imitation")
    train(config, "run")
    stored = json.loads((tmp_path / "run" / "config.json").read_text())
    assert stored["demo"] == "demo.csv" and (tmp_path / "run" / "demo.csv").exists()
    provenance = json.loads((tmp_path / "run" / "provenance.json").read_text())
    assert provenance["demo"]["source"] == str(tmp_path / "demo.csv")
    session = provenance["sessions"][0]
    assert session["packages"]["numpy"] == np.__version__ and session["packages"]["rdmp-gym"]
    assert "commit" in session["rdmp_gym"]
    # another CSV of the same name elsewhere: evaluate from there still uses the run's copy
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    wiping_demonstration(1, rng=2).to_csv(elsewhere / "demo.csv")
    (tmp_path / "demo.csv").unlink()
    monkeypatch.chdir(elsewhere)
    result = evaluate_run(tmp_path / "run", 1)
    assert result["imitation"]["return_mean"] == RunDirectory(tmp_path / "run").read_log()[0]["eval_return_mean"]
    assert not (elsewhere / "evaluation.json").exists()
    (tmp_path / "run" / "demo.csv").write_text("t,y0\n0,0\n")   # an altered copy is noticed
    with pytest.raises(ValueError, match="changed since the run started"):
        evaluate_run(tmp_path / "run", 1)
    with pytest.raises(ValueError, match="changed since the run started"):
        train(None, tmp_path / "run", resume=True)


# 6. Training on nothing stops --------------------------------------------------------------------------
def test_a_run_whose_first_update_is_all_invalid_stops_with_the_reasons(tmp_path):
    from rdmp_gym.agents.tasks import WIPE_ID

    from rdmp_gym import wiping_demonstration
    from rdmp_gym.signals.demonstrations import Demonstration

    demo = wiping_demonstration(1, rng=0)
    Demonstration(demo.t, demo.Y * 1000.0, name="millimetres").to_csv(tmp_path / "mm.csv")
    small = {"n_periodic": 10, "n_transient": 10, "n_periods": 2, "control_rate": 50}
    # a demonstration in millimetres is refused before any episode (the env's frame check) ...
    mm = TrainConfig(agent="cmaes", updates=5, rollouts=3, env_id=WIPE_ID, demo=str(tmp_path / "mm.csv"),
                     env_kwargs=small)
    with pytest.raises(ValueError, match=r"demonstration.*millimetres"):
        train(mm, tmp_path / "mm_run")
    # ... and settings under which no plan is executable stop the run after its first update, reasons counted
    config = TrainConfig(agent="cmaes", updates=5, rollouts=3, env_id=WIPE_ID,
                         env_kwargs={**small, "max_joint_speed": 1e-3})
    with pytest.raises(NoValidEpisodesError, match=r"all 3 episodes.*invalid_reason: joint_speed x3.*units"):
        train(config, tmp_path / "run")
    assert _updates(tmp_path / "run") == [0, 1]                # stopped after the first update


# 8. Broken files --------------------------------------------------------------------------------------
def test_broken_checkpoint_files_are_errors_that_name_the_file(tmp_path):
    run = train(_config(updates=1), tmp_path / "run")
    original = run.checkpoint_path.read_text()
    moved = {**json.loads(original), "update": 7}
    for broken, message in (("", r"checkpoint.json: broken JSON"), ("[1, 2]", r"checkpoint.json: not an rdmp"),
                            (json.dumps(moved), "does not match its update")):
        run.checkpoint_path.write_text(broken)
        with pytest.raises(ValueError, match=message):
            train(None, run.path, resume=True)
    run.checkpoint_path.write_text(original)
    npz = next(run.path.glob("checkpoint-*.npz"))
    npz.write_bytes(npz.read_bytes()[:50])                    # a torn array file
    with pytest.raises(ValueError, match=r"checkpoint-1.npz: does not match the sha256"):
        train(None, run.path, resume=True)
    (run.path / "config.json").write_text('{"agent": "pi2", ')
    with pytest.raises(ValueError, match=r"config.json: broken JSON"):
        train(None, run.path, resume=True)


def test_a_torn_log_line_is_dropped_with_a_warning_and_the_resume_is_exact(tmp_path, caplog):
    straight = train(_config(updates=3), tmp_path / "straight")
    run = train(_config(updates=2), tmp_path / "killed")
    with run.log_path.open("a") as handle:
        handle.write('{"update": 3, "episodes": 1')          # killed while writing the next line
    with caplog.at_level("WARNING"):
        train(_config(updates=3), run.path, resume=True)
    assert "incomplete last line" in caplog.text
    strip = [{k: v for k, v in r.items() if k != "time_s"} for r in straight.read_log()]
    assert [{k: v for k, v in r.items() if k != "time_s"} for r in run.read_log()] == strip


def test_missing_log_lines_are_an_error_not_a_silent_gap(tmp_path):
    run = train(_config(updates=3), tmp_path / "run")
    lines = run.log_path.read_text().splitlines(keepends=True)
    run.log_path.write_text("".join(lines[:2] + lines[3:]))    # update 2 lost
    with pytest.raises(ValueError, match=r"log.jsonl: holds updates \[0, 1, 3\]"):
        train(_config(updates=4), run.path, resume=True)
    run.log_path.write_text(lines[0] + "not json\n" + "".join(lines[2:]))
    with pytest.raises(ValueError, match=r"log.jsonl: line 2 is broken"):
        run.read_log()


def test_unwritable_out_is_refused_before_any_work(tmp_path, monkeypatch):
    (tmp_path / "file").write_text("")
    calls = []
    monkeypatch.setattr(Evaluator, "run", lambda self, *a: calls.append(1))
    with pytest.raises(PermissionError, match="cannot write"):
        train(_config(), tmp_path / "file" / "run")
    assert main(["train", "--out", str(tmp_path / "file" / "run"), "--env", TRACKING_ID, "--workers", "1"]) == 2
    monkeypatch.undo()
    run = train(_config(updates=1), tmp_path / "run")

    def read_only(*args, **kwargs):
        raise PermissionError(13, "Permission denied")      # what a read-only run directory gives

    monkeypatch.setattr(runs_module.os, "replace", read_only)
    monkeypatch.setattr(Evaluator, "run", lambda self, *a: calls.append(1))
    with pytest.raises(PermissionError, match="cannot write"):
        evaluate_run(run.path, 2)
    assert not calls                                          # refused before running an episode


def test_best_params_are_validated(tmp_path):
    run = train(_config(updates=1), tmp_path / "run")
    np.save(run.best_npy, np.full(50, np.nan))
    with pytest.raises(ValueError, match=r"best_params.npy: expected 50 finite"):
        evaluate_run(run.path, 1, policy="best")
    run.best_npy.write_bytes(b"\x93NUMPY garbage")
    with pytest.raises(ValueError, match=r"best_params.npy: unreadable"):
        evaluate_run(run.path, 1, policy="best")


def test_a_ppo_checkpoint_is_sb3s_zip_of_which_only_the_weights_are_read(tmp_path):
    import base64
    import io
    import zipfile

    run = train(_config("ppo", updates=1, options={}), tmp_path / "run")
    document = json.loads(run.checkpoint_path.read_text())
    model = run.path / document["files"]["b0"]
    assert model.suffix == ".zip" and zipfile.is_zipfile(model)
    marker = tmp_path / "ran"
    payload = base64.b64encode(pickle.dumps(_Payload(marker))).decode()
    rewritten = io.BytesIO()
    with zipfile.ZipFile(model) as source, zipfile.ZipFile(rewritten, "w") as target:
        for name in source.namelist():
            data = source.read(name)
            if name == "data":        # SB3 unpickles ':serialized:' entries of 'data' in PPO.load
                data = json.dumps({**json.loads(data), "evil": {":type:": "x", ":serialized:": payload}}).encode()
            target.writestr(name, data)
    model.write_bytes(rewritten.getvalue())
    document["sha256"][model.name] = runs_module.sha256_file(model)
    run.checkpoint_path.write_text(json.dumps(document))
    last = evaluate_run(run.path, 1, policy="last")
    assert last["trained"]["return_mean"] is not None
    train(_config("ppo", updates=2, options={}), run.path, resume=True)
    assert _updates(run.path) == [0, 1, 2]
    assert not marker.exists()
