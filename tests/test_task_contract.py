"""The tools read a task only through its contract: the drumming and wiping tasks declare theirs, and training,
evaluation, the printed table, the log and the figures show each task's own metrics (a task written in this file
too), success only where the env reports it, with no attribute of the task read through the face."""

from __future__ import annotations

import contextlib
import io
import json
import logging
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import gymnasium as gym
import mujoco
import numpy as np
import pytest
import rdmp_gym.envs  # noqa: F401  (registers the ids)
from rdmp_gym.agents import report
from rdmp_gym.agents.callbacks import batch_summary
from rdmp_gym.agents.cli import main
from rdmp_gym.agents.episodes import run_episode
from rdmp_gym.agents.learners import EpisodeBatch, SearchSpace, make_learner
from rdmp_gym.agents.plots import plot_policy_comparison
from rdmp_gym.agents.protocol import context_observations, path_jerk, stratified_validation_seeds, success
from rdmp_gym.agents.training import TrainConfig, train
from rdmp_gym.envs.arena import FORCE, FOUND, NETFORCE, add_contact_sensor
from rdmp_gym.envs.contract import Metric, contract_of
from rdmp_gym.envs.registration import TRACKING_ID, register_task_ids
from rdmp_gym.envs.rhythmic_env import RhythmicTaskEnv
from rdmp_gym.envs.smoothness import Smoothness
from rdmp_gym.envs.tasks import TASKS, Outcome, TaskDescription, TaskPlan, ToolPath, register_task

from rdmp_gym import Demonstration, RhythmicDMP
from rdmp_gym.synthetic.smoothness import integrated_squared_jerk

ROOT = Path(__file__).resolve().parent.parent
DRUM = "rdmp_gym/ArmarDrum-v1"
#: the smallest run of the command line: one update of two rollouts, one validation context, two test contexts
TRAIN = ["--agent", "cmaes", "--updates", "1", "--rollouts", "2", "--eval-episodes", "1", "--workers", "1"]
EVALUATE = ["--episodes", "2", "--workers", "1"]


# ------------------------------------------------------------------ the declarations
def test_the_drumming_and_wiping_tasks_declare_their_metrics_fields_and_smoothness():
    drum, wipe, wipe_v1 = (contract_of(gym.make(env_id)) for env_id in (DRUM, "rdmp_gym/ArmarWipe-v3",
                                                                         "rdmp_gym/ArmarWipe-v1"))
    assert drum.metric_keys == ("struck_fraction", "mean_abs_timing_error")
    timing = drum.metric("mean_abs_timing_error")
    assert timing.unit == "s" and not timing.higher_is_better and timing.label == "timing error (s)"
    assert "tempo" in drum.context_fields and "patch_size" not in drum.context_fields
    assert drum.context_kind is None and drum.smoothness == "jerk" and drum.has_success
    assert wipe.metric_keys == ("coverage", "force_in_band_fraction")
    assert {"patch_size", "obstacle", "sponge_start"} <= set(wipe.context_fields) and "tempo" not in wipe.context_fields
    assert callable(wipe.context_kind) and wipe.has_success
    assert (wipe.smoothness, wipe_v1.smoothness) == ("speed_normalised_jerk", "jerk")     # the versions' measures
    assert wipe.dt == gym.make("rdmp_gym/ArmarWipe-v3").unwrapped.dt and wipe.path_labels == ("x", "y", "z")


def test_a_contextual_learner_selects_the_drumming_tasks_own_context_fields():
    env = gym.make(DRUM)
    space = SearchSpace.from_env(env, context_observations(env, np.arange(4)))
    start = np.zeros(env.action_space.shape[0])
    learner = make_learner("creps", start, 4, np.random.default_rng(0), {"features": ["tempo"]}, space=space)
    assert learner.features(np.zeros((1, 6))).shape == (1, 2)                     # [1, the tempo]
    with pytest.raises(ValueError, match="patch_size"):
        make_learner("creps", start, 4, np.random.default_rng(0), {"features": ["patch_size"]}, space=space)


@pytest.mark.parametrize(("env_id", "settings"), [(DRUM, {}), ("rdmp_gym/ArmarWipe-v2", {"cup_clearance": 0.01})])
def test_path_jerk_is_the_contracts_measure_of_the_executed_path(env_id, settings):
    """The numbers of the published protocol: the wiping task's executed path (with the cup clearance) per unit of
    squared speed, the drumming plan's integrated squared jerk."""
    env = gym.make(env_id, **settings)
    base, action = env.unwrapped, 0.2 * np.ones(env.action_space.shape)
    seed = 7
    measured = path_jerk(env, action, seed)
    env.reset(seed=seed)
    if env_id == DRUM:
        assert measured == integrated_squared_jerk(base.action_path(action), base.dt)
    else:
        path = base.task.executed_path(base.action_to_params(action), base.context)
        assert measured == Smoothness.speed_normalised(path, base.dt)


# ------------------------------------------------------------------ success and the log
def test_success_is_the_envs_own_and_never_made_up_from_the_metrics():
    k = 3
    batch = EpisodeBatch(np.zeros((k, 1)), np.zeros(k), np.zeros((k, 2)), np.ones(k, bool), np.arange(k),
                         {"coverage": np.ones(k), "force_in_band_fraction": np.ones(k)})
    assert success(batch) is None
    summary = batch_summary(batch, "eval_")
    assert summary["eval_success"] is None and summary["eval_coverage"] == 1.0
    reported = EpisodeBatch(*(getattr(batch, name) for name in ("actions", "returns", "cost_traces", "valid",
                                                                 "seeds")), success=np.array([True, False, True]))
    assert success(reported).tolist() == [True, False, True] and "eval_coverage" not in batch_summary(reported, "eval_")


def test_a_metric_undefined_in_some_episodes_is_averaged_over_those_that_have_it():
    k = 4
    batch = EpisodeBatch(np.zeros((k, 1)), np.zeros(k), np.zeros((k, 2)), np.ones(k, bool), np.arange(k),
                         {"mean_abs_timing_error": np.array([0.02, np.nan, 0.04, np.nan]),
                          "struck_fraction": np.full(k, np.nan)})
    summary = batch_summary(batch, "")
    assert summary["mean_abs_timing_error"] == pytest.approx(0.03) and summary["struck_fraction"] is None


# ------------------------------------------------------------------ the figure
@pytest.mark.parametrize("shape", [(50,), (50, 1), (50, 2), (50, 7)])
def test_the_comparison_figure_draws_paths_of_one_or_more_dimensions(tmp_path, shape):
    rng = np.random.default_rng(0)
    paths = {"imitation": rng.normal(size=shape), "trained": rng.normal(size=shape)}
    summaries = {name: {"intervals": {"return": {"estimate": -1.0, "low": -1.5, "high": -0.5, "n": 2}}}
                 for name in paths}
    target = tmp_path / "comparison.png"
    plot_policy_comparison(paths, summaries, target, "paths", (("return", "return"), ("success", "success rate")),
                           labels=("q",), dt=0.02)
    assert target.stat().st_size > 10_000


# ------------------------------------------------------------------ the command line on the drumming task
def _run_command(argv: list[str]) -> str:
    """``rdmp-gym ARGV``: what it printed (AssertionError with its error where it failed)."""
    printed, errors = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(printed), contextlib.redirect_stderr(errors):
        status = main(argv)
    assert status == 0, errors.getvalue()[-3000:]
    return printed.getvalue()


def _train_and_evaluate(run: Path, env_id: str) -> str:
    """Train on ``env_id`` into ``run`` and evaluate it from the command line; the evaluation's printout."""
    _run_command(["train", "--env", env_id, *TRAIN, "--out", str(run)])
    return _run_command(["evaluate", str(run), *EVALUATE])


@pytest.fixture(scope="module")
def drum_run(tmp_path_factory):
    """The drumming task trained and evaluated from the command line: what the tools know of the task comes from its
    contract alone (the face forwards none of the task's attributes)."""
    run = tmp_path_factory.mktemp("drum") / "run"
    return run, _train_and_evaluate(run, DRUM)


def test_what_the_agents_read_of_a_wiping_env_needs_no_forwarding_of_the_task():
    env = gym.make("rdmp_gym/ArmarWipe-v3", cup_clearance=0.01)
    base, zeros = env.unwrapped, np.zeros(env.action_space.shape)
    assert isinstance(base, RhythmicTaskEnv) and not hasattr(base, "groups") and "periodic" in base.task.groups
    seeds = stratified_validation_seeds(env, 2, pool=4)
    space = SearchSpace.from_env(env, context_observations(env, seeds))
    assert "patch_size" in space.context_names and space.context_gate is not None
    theta = base.action_to_params(zeros)
    assert base.policy_dmp(theta).period == base.dmp.period and "periodic" in base.param_slices()
    assert np.isfinite(path_jerk(env, zeros, int(seeds[0])))
    episode = run_episode(env, zeros, int(seeds[0]), None)
    assert set(episode["metrics"]) == {"coverage", "force_in_band_fraction"} and episode["success"] is not None


def test_the_drumming_evaluation_table_names_the_return_and_the_tasks_metrics(drum_run):
    _, printed = drum_run
    header = next(line for line in printed.splitlines() if line.strip().startswith("policy"))
    assert "return" in header and "struck fraction" in header and "timing error" in header
    assert "success rate" in header and "coverage" not in printed
    assert re.search(r"paired gain .*return .*struck fraction", printed)


def test_the_drumming_evaluation_writes_its_metrics_and_figure(drum_run):
    run, _ = drum_run
    result = json.loads((run / "evaluation.json").read_text())
    assert [m["key"] for m in result["metrics"]] == ["struck_fraction", "mean_abs_timing_error"]
    assert [m["label"] for m in result["metrics"]] == ["struck fraction", "timing error (s)"]
    for name in ("imitation", "trained"):
        summary = result[name]
        assert len(summary["struck_fraction"]) == 2 and "struck_fraction_mean" in summary
        assert {"return", "success", "struck_fraction", "jerk_ratio"} <= set(summary["intervals"])
    assert result["imitation"]["jerk_ratio_mean"] == pytest.approx(1.0)
    assert (run / "evaluation.png").stat().st_size > 10_000


def test_the_drumming_log_has_the_tasks_columns_by_key(drum_run):
    run, _ = drum_run
    records = [json.loads(line) for line in (run / "log.jsonl").read_text().splitlines()]
    assert {"eval_struck_fraction", "eval_mean_abs_timing_error", "eval_success"} <= set(records[0])
    assert {"struck_fraction", "mean_abs_timing_error", "return_mean"} <= set(records[1])
    assert not any("coverage" in key or "force_in_band" in key for record in records for key in record)
    assert (run / "dmp.json").is_file()                                      # the face's policy_dmp


def test_a_step_based_env_of_one_actuator_is_evaluated_with_its_return_and_figure(tmp_path):
    """Under the black-box wrapper (its contract: no success reported by the env) the table shows the return, and
    the figure draws the one joint's path against time."""
    printed = _train_and_evaluate(tmp_path / "run", "InvertedPendulum-v5")
    header = next(line for line in printed.splitlines() if line.strip().startswith("policy"))
    assert "return" in header and "success" not in header and "coverage" not in printed
    assert (tmp_path / "run" / "evaluation.png").stat().st_size > 10_000


def test_evaluate_writes_the_evaluation_even_when_the_figure_cannot_be_drawn(tmp_path, monkeypatch, caplog):
    run = train(TrainConfig(agent="cmaes", updates=1, rollouts=2, env_id=TRACKING_ID, eval_episodes=1, workers=1),
                tmp_path / "run")

    def broken(*args: Any, **kwargs: Any) -> None:
        raise IndexError("the figure broke")

    monkeypatch.setattr(report, "plot_policy_comparison", broken)
    with caplog.at_level(logging.WARNING, logger="rdmp_gym.agents.report"):
        result = report.evaluate_run(run.path, 2)
    saved = json.loads((run.path / "evaluation.json").read_text())
    assert saved["trained"]["returns"] == result["trained"]["returns"] and not (run.path / "evaluation.png").exists()
    assert "the figure broke" in caplog.text
    assert not saved["has_success"] and saved["trained"]["success"] is None              # none made up
    assert saved["trained"]["success_rate"] is None and "success" not in saved["trained"]["intervals"]
    assert [m["key"] for m in saved["metrics"]] == ["rms_error"] and "rms_error" in saved["trained"]["intervals"]


# ------------------------------------------------------------------ a task written here
_POINTER = """
<mujoco model="pointer">
  <worldbody>
    <geom name="rod" type="capsule" fromto="0 0 0 -0.08 0 0" size="0.006" contype="6" conaffinity="1"/>
    <site name="point" pos="-0.086 0 0" size="0.003"/>
  </worldbody>
</mujoco>
"""


class KnockTask(TaskDescription):
    """Knock on the table with a pointer once per second near a point (the context); its metric: the knocks."""

    name = "Knock"
    groups = ("periodic", "transient", "amplitude")
    tool_site = "point"
    duration = 4.0
    metrics = (Metric("knocks", "knocks counted"),)

    def compose(self, spec: mujoco.MjSpec, robot, robot_prefix: str, tool_prefix: str) -> None:
        mount = robot.tool_mount
        frame = spec.body(robot_prefix + mount.body).add_frame(pos=list(mount.pos), quat=list(mount.quat))
        spec.attach(mujoco.MjSpec.from_string(_POINTER), frame=frame, prefix=tool_prefix)
        add_contact_sensor(spec, "knock", (mujoco.mjtObj.mjOBJ_GEOM, tool_prefix + "rod"),
                           (mujoco.mjtObj.mjOBJ_GEOM, "table_top"), FOUND | FORCE, NETFORCE)

    def imitation(self) -> RhythmicDMP:
        t = np.arange(0.0, 5.0, 0.01)
        come = np.clip(t, 0, 1)[:, None] ** 2 * (3 - 2 * np.clip(t, 0, 1)[:, None])
        knock = np.c_[np.zeros_like(t), np.zeros_like(t), 0.03 + 0.033 * np.cos(2 * np.pi * (t - 1.0))]
        return RhythmicDMP.fit(Demonstration(t, np.array([0.0, 0.05, 0.1]) + come * (knock - [0.0, 0.05, 0.1])),
                               n_periodic=8, n_transient=8)

    def context_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        return np.array([0.0, -0.08]), np.array([0.08, 0.05])

    def context_fields(self) -> Mapping[str, tuple[int, int]]:
        return {"point": (0, 2)}

    def sample_context(self, rng: np.random.Generator, options: Mapping[str, Any] | None) -> Any:
        low, high = self.context_bounds()
        point = np.asarray((options or {}).get("point", rng.uniform(low, high)), dtype=np.float64)
        return type("KnockContext", (), {"point": point, "vector": lambda self: self.point})()

    def place(self, model: mujoco.MjModel, context: Any) -> None:
        """Nothing to move: the point is where the pointer knocks."""

    def plan(self, dmp: RhythmicDMP, theta: np.ndarray, extras: np.ndarray, context: Any, times: np.ndarray,
             table_origin: np.ndarray) -> TaskPlan:
        return TaskPlan(dmp.with_params(theta, self.groups).rollout(times), table_origin + np.r_[context.point, 0.0],
                        np.eye(3))

    def evaluate(self, path: ToolPath, context: Any, sensor: Mapping[str, slice]) -> Outcome:
        pressing = np.abs(path.sensors[:, sensor["knock"]][:, 3]) > 0.5
        knocks = int(np.sum(np.diff(pressing.astype(int)) == 1))
        cost = np.zeros(len(path.plan.path))
        cost[-1] = abs(knocks - 3) / 3.0
        return Outcome({"knocks": -float(cost[-1])}, cost, {"knocks": knocks}, () if knocks >= 2 else ("knocks",))


@pytest.fixture(scope="module")
def knock_id():
    register_task("knock", KnockTask, id_name="Knock")
    yield register_task_ids("knock", robots=("armar3",))[0]
    TASKS.pop("knock")


def test_a_task_written_here_is_trained_and_evaluated_with_its_own_metric(knock_id, tmp_path):
    assert contract_of(gym.make(knock_id)).context_fields == {"point": (0, 2)}
    printed = _train_and_evaluate(tmp_path / "run", knock_id)
    header = next(line for line in printed.splitlines() if line.strip().startswith("policy"))
    assert "knocks counted" in header and "return" in header
    result = json.loads((tmp_path / "run" / "evaluation.json").read_text())
    assert [m["key"] for m in result["metrics"]] == ["knocks"] and "knocks" in result["trained"]["intervals"]
    records = [json.loads(line) for line in (tmp_path / "run" / "log.jsonl").read_text().splitlines()]
    assert "eval_knocks" in records[0] and "knocks" in records[1]


# ------------------------------------------------------------------ the seam
#: the tasks' info keys that only their own folders may name
_TASK_KEYS = ("coverage", "force_in_band", "force_in_band_fraction", "struck_fraction", "mean_abs_timing_error",
              "timing_error", "rms_error")


def test_the_agents_name_no_tasks_info_key():
    pattern = re.compile("[\"'](" + "|".join(_TASK_KEYS) + ")[\"']")
    found = [f"{path.relative_to(ROOT)}: {match.group(0)}" for path in (ROOT / "agents").rglob("*.py")
             for match in pattern.finditer(path.read_text())]
    assert not found
