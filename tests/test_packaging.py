"""Packaging and the ``rdmp-gym`` command: the wheel holds every package, the core-only install runs ``fit``
and names the extra the other commands need, ``--version``, defaults in every help text, ``--time-column``
and ``--rate``, a non-episodic ``--env`` is a clear error."""

import json
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from rdmp_gym.agents import cli

from rdmp_gym import Demonstration, wiping_demonstration

ROOT = Path(__file__).resolve().parent.parent
LAYERS = {"rdmp_gym": ROOT / "rdmp_gym", "rdmp_gym/envs": ROOT / "envs", "rdmp_gym/agents": ROOT / "agents"}


@pytest.fixture(scope="module")
def wheel(tmp_path_factory):
    out = tmp_path_factory.mktemp("dist")
    result = subprocess.run([sys.executable, "-m", "pip", "wheel", "-v", "--no-deps", "--wheel-dir", str(out),
                             str(ROOT)], capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    return next(out.glob("rdmp_gym-*.whl")), result.stdout + result.stderr


def test_wheel_holds_every_module_of_the_three_layers_the_xml_and_the_license(wheel):
    path, _ = wheel
    names = set(zipfile.ZipFile(path).namelist())
    expected = {f"{prefix}/{file.relative_to(folder).as_posix()}" for prefix, folder in LAYERS.items()
                for file in folder.rglob("*.py") if "__pycache__" not in file.parts}
    assert "rdmp_gym/agents/learners/__init__.py" in expected
    assert expected <= names, sorted(expected - names)
    assert "rdmp_gym/envs/robots/armar3/legacy_scene.xml" in names
    assert any(name.endswith(".dist-info/licenses/LICENSE") for name in names)
    metadata = zipfile.ZipFile(path).read(f"rdmp_gym-{cli.__version__}.dist-info/METADATA").decode()
    assert f"Version: {cli.__version__}\n" in metadata and "License-Expression: BSD-3-Clause" in metadata


def test_build_prints_no_setuptools_warning_and_the_metadata_is_clean(wheel):
    _, log = wheel
    warnings = [line for line in log.splitlines() if "Warning" in line or "deprecated" in line.lower()]
    assert warnings == []
    pyproject = (ROOT / "pyproject.toml").read_text()
    assert 'license = "BSD-3-Clause"' in pyproject and (ROOT / "LICENSE").read_text().startswith("BSD 3-Clause")
    agents = next(line for line in pyproject.splitlines() if line.startswith("agents = "))
    assert '"torch>=2.3,<3"' in agents   # bounded in the extra; the exact CPU build is pinned by the constraints file
    assert "torch==2.13.0" in (ROOT / ".ci" / "constraints-cpu.txt").read_text()


_BLOCK_EXTRAS = """
import sys
class _Block:
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in {"gymnasium", "mujoco", "cma", "tqdm", "stable_baselines3", "torch", "imageio",
                                   "matplotlib", "filelock", "ray", "tensorboard"}:
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
sys.meta_path.insert(0, _Block())
"""

_RUN_EACH = _BLOCK_EXTRAS + """
import contextlib, io, json, traceback
from rdmp_gym.agents.cli import main
results = []
for args in json.loads(sys.argv[1]):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(args)
        except SystemExit as exit_:          # as the interpreter maps sys.exit's argument to the exit status
            code = 0 if exit_.code is None else exit_.code if isinstance(exit_.code, int) else 1
        except BaseException:                # an uncaught error: its traceback and status 1, as the interpreter's
            traceback.print_exc()
            code = 1
    results.append((code, out.getvalue(), err.getvalue()))
sys.__stdout__.write(json.dumps(results))
"""


def _core_only(*commands, cwd):
    """Run each command (a list of arguments) as on an install without the extras (their modules cannot be
    imported), in order, in one fresh process (the interpreter's start and the core's import are most of a
    command's cost): per command ``(exit status, stdout, stderr)``."""
    result = subprocess.run([sys.executable, "-c", _RUN_EACH, json.dumps([list(c) for c in commands])],
                            capture_output=True, text=True, cwd=cwd, timeout=240, env={**os.environ, "PYTHONPATH": ""})
    assert result.returncode == 0, result.stderr[-3000:]
    return [subprocess.CompletedProcess(command, code, out, err)
            for command, (code, out, err) in zip(commands, json.loads(result.stdout), strict=True)]


@pytest.mark.slow          # CI's wheel check (.ci/wheel-check.sh) runs the same commands on the installed wheel
def test_core_install_runs_help_and_fit_and_names_the_extra_for_train(tmp_path):
    demo = wiping_demonstration(1, rng=0)
    np.savetxt(tmp_path / "rec.csv", np.column_stack([demo.t, demo.Y]), delimiter=",", header="t,x,y,z", comments="")
    refusals = ("train", "evaluate", "main")
    help_text, fit_help, fit, whole, plot, *refused = _core_only(
        ["--help"], ["fit", "--help"],
        ["fit", "--n-periodic", "10", "--n-transient", "10", "--out", str(tmp_path / "fit")],
        ["fit", "--demo", str(tmp_path / "rec.csv"), "--n-periodic", "12", "--n-transient", "12",
         "--out", str(tmp_path / "whole")],
        ["fit", "--plot", "--out", str(tmp_path / "plot")],
        *([command, *([str(tmp_path / "run")] if command == "evaluate" else ["--out", str(tmp_path / "run")])]
          for command in refusals), cwd=tmp_path)
    assert help_text.returncode == 0 and "fit" in help_text.stdout and "agents extra" in help_text.stdout
    assert fit_help.returncode == 0
    assert fit.returncode == 0, fit.stderr
    assert (tmp_path / "fit" / "dmp.json").is_file() and "RMS error" in fit.stdout
    assert whole.returncode == 0, whole.stderr
    assert (tmp_path / "whole" / "report.json").is_file()
    assert plot.returncode == 2 and 'pip install "rdmp-gym[plots]"' in plot.stderr and "Traceback" not in plot.stderr
    for command, result in zip(refusals, refused, strict=True):
        assert result.returncode == 2 and 'pip install "rdmp-gym[agents]"' in result.stderr, command
        assert "Traceback" not in result.stderr and not (tmp_path / "run").exists()


def test_version_flag(capsys):
    assert cli.main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"rdmp-gym {cli.__version__}"


def test_every_command_has_help_with_defaults_and_the_launcher_describes_it_as_its_flags_do(capsys):
    from rdmp_gym.agents.cycle_command import CycleCommand
    from rdmp_gym.agents.fit_command import FitCommand
    from rdmp_gym.agents.run_commands import EvaluateCommand, MainCommand, TrainCommand

    kinds = {"train": TrainCommand, "evaluate": EvaluateCommand, "fit": FitCommand, "main": MainCommand,
             "cycles": CycleCommand}
    assert set(kinds) == set(cli.COMMANDS)
    for name, kind in kinds.items():
        assert cli.COMMANDS[name][2] == kind.__doc__, name
        assert cli.main([name, "--help"]) == 0
        text = " ".join(capsys.readouterr().out.replace("│", " ").split())
        assert kind.__doc__ in text and "(default: " in text, name


def test_fit_reads_a_time_column_and_resamples_uneven_stamps(tmp_path, capsys):
    demo = wiping_demonstration(1, rng=0)
    jitter = demo.t + np.random.default_rng(0).uniform(-2e-3, 2e-3, demo.t.size) * (np.arange(demo.t.size) > 0)
    path = tmp_path / "recording.csv"
    np.savetxt(path, np.column_stack([jitter, demo.Y]), delimiter=",", header="time,x,y,z", comments="")
    code = cli.main(["fit", "--demo", str(path), "--time-column", "time", "--n-periodic", "20",
                     "--n-transient", "20", "--out", str(tmp_path / "b")])
    output = capsys.readouterr().out
    assert code == 0 and (tmp_path / "b" / "dmp.json").is_file()
    assert float(output.split("period ")[1].split(" s")[0]) == pytest.approx(demo.truth.period, rel=0.03)
    assert float(output.split("start error ")[1].split(" mm")[0]) < 10.0


def test_a_non_episodic_env_is_a_clear_error(tmp_path, capsys):
    code = cli.main(["train", "--env", "CartPole-v1", "--updates", "1", "--rollouts", "2", "--workers", "1",
                     "--out", str(tmp_path / "run")])
    err = capsys.readouterr().err
    assert code == 2 and "not an episodic DMP env" in err and "Traceback" not in err


def test_train_takes_a_recording_with_a_time_column_and_uneven_stamps(tmp_path):
    demo = wiping_demonstration(1, rng=0)
    jitter = demo.t + np.random.default_rng(1).uniform(-2e-3, 2e-3, demo.t.size) * (np.arange(demo.t.size) > 0)
    path = tmp_path / "recording.csv"
    np.savetxt(path, np.column_stack([jitter, demo.Y]), delimiter=",", header="time,x,y,z", comments="")
    out = tmp_path / "run"
    code = cli.main(["train", "--env", "rdmp_gym/DMPTracking-v0", "--demo", str(path), "--time-column", "time",
                     "--rate", "100", "--updates", "1", "--rollouts", "2", "--workers", "1", "--env-option",
                     "n_periodic", "8", "n_transient", "8", "duration", "3", "--out", str(out)])
    assert code == 0
    saved = Demonstration.from_npz(out / "demo.npz")
    assert np.allclose(np.diff(saved.t), 0.01) and (out / "dmp.json").is_file()
