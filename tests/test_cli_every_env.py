"""The command line on every kind of env: repeated ``--env-option``/``--reset-option`` flags add up, the env's settings
are env options (a flag that is not the command's is refused with the ``--env-option`` to give instead), the run's
flags are :class:`TrainConfig`'s fields, a user's env registered with a class entry point and a wrapped Gymnasium
env train, resume and evaluate, and ``--video`` is refused before any work where the env cannot record."""

from __future__ import annotations

import contextlib
import dataclasses
import io
import json

import gymnasium as gym
import mujoco
import numpy as np
import pytest
from rdmp_gym.agents import cli
from rdmp_gym.agents.run_commands import RUN_FIELDS, env_value, parse_main, parse_train, train_config
from rdmp_gym.agents.training import TrainConfig
from rdmp_gym.envs.registration import TRACKING_ID, env_settings
from rdmp_gym.envs.specs import is_episodic

#: the tracking task kept small (a run of one update takes about a second)
TINY_TRACKING = ["--agent", "cmaes", "--env", TRACKING_ID, "--workers", "1", "--updates", "1", "--rollouts", "2",
                 "--env-option", "n_periodic", "6", "n_transient", "6", "duration", "2"]
#: one hinge under a motor
_HINGE_XML = """<mujoco><option timestep="0.01"/><worldbody><body name="arm"><joint name="hinge" type="hinge"
axis="0 1 0" damping="0.05"/><geom type="capsule" fromto="0 0 0 0 0 -0.3" size="0.02" mass="0.2"/></body></worldbody>
<actuator><motor joint="hinge" ctrlrange="-1 1" ctrllimited="true"/></actuator></mujoco>"""
HINGE_ID = "rdmp_gym_tests/TinyHinge-v0"


class TinyHinge(gym.Env):
    """A user's step-based env: one actuated hinge (MuJoCo), observation ``(q, qd)``, reward ``-(q - target)**2``."""

    metadata = {"render_modes": []}   # noqa: RUF012  (gymnasium's class attribute)

    def __init__(self, target: float = 0.3) -> None:
        self.model = mujoco.MjModel.from_xml_string(_HINGE_XML)
        self.data = mujoco.MjData(self.model)
        self.dt = 2 * self.model.opt.timestep
        self.target = float(target)
        self.action_space = gym.spaces.Box(-1.0, 1.0, (1,), np.float32)
        self.observation_space = gym.spaces.Box(-np.inf, np.inf, (2,), np.float64)

    def _observe(self) -> np.ndarray:
        return np.array([self.data.qpos[0], self.data.qvel[0]])

    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        super().reset(seed=seed)
        mujoco.mj_resetData(self.model, self.data)
        self.data.qpos[0] = self.np_random.uniform(-0.05, 0.05)
        mujoco.mj_forward(self.model, self.data)
        return self._observe(), {}

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict]:
        self.data.ctrl[:] = action
        mujoco.mj_step(self.model, self.data, nstep=2)
        return self._observe(), -float((self.data.qpos[0] - self.target) ** 2), False, False, {}


if HINGE_ID not in gym.registry:
    gym.register(id=HINGE_ID, entry_point=TinyHinge, max_episode_steps=50)


# ------------------------------------------------------------------ parsing (no env is built)
def test_repeated_env_and_reset_options_add_up_and_a_repeated_key_takes_its_last_value():
    command = parse_train(["--out", "runs/x", "--agent", "cmaes", "--env", "Swimmer-v5",
                           "--env-option", "p_gains", "5", "--env-option", "ctrl_cost_weight", "0.0",
                           "--env-option", "groups", '["periodic", "amplitude"]', "duration", "0.4",
                           "--env-option", "p_gains", "6", "--reset-option", "a", "1", "--reset-option", "b", "null"])
    assert command.env_kwargs == {"p_gains": 6, "ctrl_cost_weight": 0.0, "groups": ["periodic", "amplitude"],
                                  "duration": 0.4}
    assert command.reset_options == {"a": 1, "b": None}
    assert train_config(command).env_kwargs == command.env_kwargs
    main = parse_main(["--env-option", "style", "2", "--env-option", "cup_clearance", "None"])
    assert main.env_kwargs == {"cup_clearance": None, "style": 2}        # the main job's keyword, replaced


@pytest.mark.parametrize(("text", "value"), [("2", 2), ("0.5", 0.5), ("true", True), ("True", True), ("null", None),
                                             ("None", None), ('["periodic", "amplitude"]', ["periodic", "amplitude"]),
                                             ('"2"', "2"), ("Swimmer-v5", "Swimmer-v5"), ("runs/x/dmp.json",
                                                                                         "runs/x/dmp.json")])
def test_an_env_option_value_is_json_where_it_parses(text, value):
    assert env_value(text) == value


@pytest.mark.parametrize("flag", ["--style", "--groups", "--n-periodic", "--n-transient", "--duration", "--dmp"])
def test_a_setting_of_the_env_given_as_a_flag_is_refused_with_the_env_option_to_give(flag, tmp_path, capsys):
    assert cli.main(["train", "--out", str(tmp_path / "run"), flag, "2"]) == 2
    key = flag[2:].replace("-", "_")
    assert f"--env-option {key} VALUE" in capsys.readouterr().err
    assert not (tmp_path / "run").exists()


def test_an_env_option_without_its_value_is_refused(tmp_path, capsys):
    assert cli.main(["train", "--out", str(tmp_path / "run"), "--env-option", "style"]) == 2
    assert "--env-option: expected KEY VALUE pairs" in capsys.readouterr().err


def test_the_run_flags_are_the_configs_fields_each_with_its_default_and_help(capsys):
    assert cli.main(["train", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.replace("│", " ").split())
    flags = {"env_id": "--env", "env_kwargs": "--env-option KEY VALUE", "reset_options": "--reset-option KEY VALUE"}
    for name in RUN_FIELDS:
        assert flags.get(name, "--" + name.replace("_", "-")) in text, name
    assert set(RUN_FIELDS) == {item.name for item in dataclasses.fields(TrainConfig)} - {"options"}
    assert "--updates INT number of updates (default: 30)" in text
    assert "(default: rdmp_gym/ArmarWipe-v3)" in text and "--options.sigma" in text


def test_a_demonstration_goes_to_envs_that_take_one_and_is_refused_by_the_others(tmp_path):
    assert TrainConfig(env_id=TRACKING_ID, demo="recording.csv").demo == "recording.csv"
    assert TrainConfig(agent="cmaes", env_id="Swimmer-v5", demo="joints.csv").demo == "joints.csv"
    with pytest.raises(ValueError, match="demo: rdmp_gym/ArmarDrum-v1 takes no demonstration"):
        TrainConfig(agent="cmaes", env_id="rdmp_gym/ArmarDrum-v1", demo="recording.csv")


def test_an_env_is_told_episodic_or_step_based_by_its_class():
    assert is_episodic(TRACKING_ID) and is_episodic("rdmp_gym/ArmarWipe-v3")
    assert not is_episodic(HINGE_ID) and not is_episodic("InvertedPendulum-v5")
    env_settings(HINGE_ID, {"target": 0.2, "p_gains": 1.0})       # the env's keyword and the wrapper's setting
    with pytest.raises(ValueError, match="'targte' is neither a setting of the rhythmic black-box wrapper"):
        env_settings(HINGE_ID, {"targte": 0.2})


# ------------------------------------------------------------------ runs
def _run_cli(argv: list[str]) -> tuple[int, str]:
    """``cli.main(argv)`` and what it printed (for the module's fixtures, which capsys does not reach)."""
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        code = cli.main(argv)
    return code, printed.getvalue()


@pytest.fixture(scope="module")
def tracking_run(tmp_path_factory):
    """A finished one-update run on the tracking task (an env that cannot record episodes)."""
    out = tmp_path_factory.mktemp("tracking") / "run"
    assert _run_cli(["train", "--out", str(out), *TINY_TRACKING])[0] == 0
    return out


@pytest.fixture(scope="module")
def pendulum_run(tmp_path_factory):
    """InvertedPendulum-v5 (a Gymnasium env, under the black-box wrapper) trained for one update from the command
    line, and what the command printed."""
    out = tmp_path_factory.mktemp("pendulum") / "run"
    code, printed = _run_cli(["train", "--agent", "cmaes", "--env", "InvertedPendulum-v5", "--updates", "1",
                              "--rollouts", "2", "--workers", "1", "--env-option", "duration", "1.0",
                              "--env-option", "p_gains", "1.0", "--out", str(out)])
    assert code == 0
    return out, printed


def test_video_is_refused_before_any_run_directory_is_written(tmp_path, capsys):
    assert cli.main(["train", "--out", str(tmp_path / "run"), "--video", *TINY_TRACKING]) == 2
    assert "--video: rdmp_gym/DMPTracking-v0 cannot record an episode" in capsys.readouterr().err
    assert not (tmp_path / "run").exists()
    assert cli.main(["main", "--out", str(tmp_path / "main"), "--video", *TINY_TRACKING]) == 2
    assert not (tmp_path / "main").exists()


def test_video_is_refused_before_the_evaluation(tracking_run, capsys):
    assert cli.main(["evaluate", str(tracking_run), "--episodes", "1", "--workers", "1", "--video"]) == 2
    assert "cannot record an episode" in capsys.readouterr().err
    assert not (tracking_run / "evaluation.json").exists()


def test_a_users_env_with_a_class_entry_point_trains_and_evaluates(tmp_path, capsys):
    out = tmp_path / "hinge"
    assert cli.main(["train", "--agent", "cmaes", "--env", HINGE_ID, "--updates", "1", "--rollouts", "2",
                     "--workers", "1", "--env-option", "p_gains", "2.0", "--env-option", "target", "0.2",
                     "--out", str(out)]) == 0
    config = json.loads((out / "config.json").read_text())
    assert config["env_id"] == HINGE_ID and config["env_kwargs"] == {"p_gains": 2.0, "target": 0.2}
    assert cli.main(["evaluate", str(out), "--episodes", "2", "--workers", "1"]) == 0
    assert "return" in capsys.readouterr().out
    assert json.loads((out / "evaluation.json").read_text())["episodes"] == 2


def test_a_wrapped_gymnasium_env_trains_from_the_command_line(pendulum_run):
    out, printed = pendulum_run
    assert "return" in printed
    config = json.loads((out / "config.json").read_text())
    assert config["env_id"] == "InvertedPendulum-v5" and config["env_kwargs"] == {"duration": 1.0, "p_gains": 1.0}


def test_a_wrapped_gymnasium_env_resumes_with_its_env_options(pendulum_run, capsys):
    out, _ = pendulum_run
    assert cli.main(["train", "--agent", "cmaes", "--out", str(out), "--resume", "--updates", "2"]) == 0
    assert [json.loads(line)["update"] for line in (out / "log.jsonl").read_text().splitlines()] == [0, 1, 2]
    assert json.loads((out / "config.json").read_text())["env_kwargs"] == {"duration": 1.0, "p_gains": 1.0}
    capsys.readouterr()
    assert cli.main(["train", "--agent", "cmaes", "--out", str(out), "--resume", "--updates", "2",
                     "--env-option", "duration", "0.8"]) == 2
    assert "--env-option duration" in capsys.readouterr().err        # a resumed run keeps its env settings


def test_a_wrapped_gymnasium_env_evaluates_from_the_command_line(pendulum_run, capsys):
    out, _ = pendulum_run
    assert cli.main(["evaluate", str(out), "--episodes", "2", "--workers", "1"]) == 0
    assert "return" in capsys.readouterr().out
    assert json.loads((out / "evaluation.json").read_text())["episodes"] == 2


def test_a_setting_the_wrapper_refuses_names_the_env_option_that_sets_it(tmp_path, capsys):
    code = cli.main(["train", "--agent", "cmaes", "--env", "InvertedPendulum-v5", "--workers", "1", "--env-option",
                     "duration", "1.01", "--env-option", "p_gains", "1.0", "--out", str(tmp_path / "r")])
    assert code == 2
    assert "set it with --env-option duration VALUE" in capsys.readouterr().err
    assert not (tmp_path / "r").exists()
