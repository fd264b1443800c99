"""Settings that make success impossible are refused, and every error names its argument: the drumming task's
settings and reset options, the task registry, the step twins' refusals and the checkpoint's fields."""

from __future__ import annotations

import json
import os

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import gymnasium as gym
import numpy as np
import pytest
import rdmp_gym.envs  # noqa: F401  (registers the ids)
from rdmp_gym.agents.tasks import TaskSpec
from rdmp_gym.agents.training import TrainConfig, train
from rdmp_gym.envs.registration import TRACKING_ID, register_task_ids
from rdmp_gym.envs.tasks import BUILT_IN, TASKS, register_task
from rdmp_gym.envs.tasks.drumming import DrumContextSpec, DrumTask, Metronome


@pytest.fixture(scope="module")
def drum():
    return DrumTask()


def _context(task, **options):
    return task.sample_context(np.random.default_rng(0), options)


# ------------------------------------------------------------------ 1. the drumming task's settings
@pytest.mark.parametrize(("settings", "error", "name"), [
    ({"max_jerk_ratio": -1}, ValueError, "max_jerk_ratio"),
    ({"max_jerk_ratio": 0.5}, ValueError, "max_jerk_ratio"),      # the imitation itself (ratio 1) would fail
    ({"max_jerk_ratio": np.nan}, ValueError, "max_jerk_ratio"),
    ({"rest_speed": -1}, ValueError, "rest_speed"),
    ({"rest_speed": 0.0}, ValueError, "rest_speed"),
    ({"impulse_band": (0.1,)}, ValueError, "impulse_band"),
    ({"impulse_band": (np.nan, 1.0)}, ValueError, "impulse_band"),
    ({"impulse_band": (0.1, np.nan)}, ValueError, "impulse_band"),
    ({"impulse_band": (1.0, 0.1)}, ValueError, "impulse_band"),
    ({"impulse_band": "ab"}, TypeError, "impulse_band"),
    ({"tolerance": True}, TypeError, "tolerance"),
    ({"tolerance": np.nan}, ValueError, "tolerance"),
    ({"tolerance": 0.0}, ValueError, "tolerance"),
    ({"context": {"tempo": (60.0, 90.0)}}, TypeError, "context"),
    ({"context": DrumContextSpec(change_window=(3.0, 6.9))}, ValueError, "change_window"),
])
def test_drumming_settings_that_make_success_impossible_are_refused_by_name(settings, error, name):
    with pytest.raises(error, match=name):
        DrumTask(**settings)


def test_the_env_refuses_them_before_building_its_scene():
    with pytest.raises(ValueError, match=r"max_jerk_ratio: expected a number >= 1"):
        gym.make("rdmp_gym/ArmarDrum-v1", max_jerk_ratio=-1)


def test_valid_drumming_settings_keep_their_values():
    task = DrumTask(tolerance=0.03, impulse_band=(0, 2), max_jerk_ratio=1, rest_speed=0.05)
    assert (task.tolerance, task.impulse_band, task.max_jerk_ratio, task.rest_speed) == (0.03, (0.0, 2.0), 1.0, 0.05)
    default = DrumTask()
    assert (default.tolerance, default.impulse_band, default.max_jerk_ratio, default.rest_speed) == (
        0.05, (0.1, 1.0), 2.0, 0.02)


@pytest.mark.parametrize(("fields", "error"), [
    ({"tempo": (0.0, 100.0)}, ValueError), ({"tempo": "fast"}, TypeError), ({"drum_x": (0.1, 0.0)}, ValueError),
    ({"drum_y": (0.0, np.nan)}, ValueError), ({"drum_height": (0.0, 0.1)}, ValueError),
    ({"change_factor": (-1.0, 1.2)}, ValueError), ({"change_window": (-1.0, 2.0)}, ValueError),
    ({"drum_tilt": 2.0}, ValueError), ({"drum_tilt": True}, TypeError),
])
def test_the_context_ranges_are_checked_by_field(fields, error):
    with pytest.raises(error, match=next(iter(fields))):
        DrumContextSpec(**fields)


def test_the_metronome_refuses_a_time_or_tempo_it_cannot_keep():
    with pytest.raises(ValueError, match="near"):
        Metronome.changing_at_beat(90.0, 100.0, np.nan, 0.0, 0.5)
    with pytest.raises(ValueError, match="tempo"):
        Metronome(0.0, 90.0, np.inf, 0.0, 0.5)


# ------------------------------------------------------------------ 2. the drumming reset options
def test_a_change_time_after_the_episodes_last_beat_is_refused_with_the_valid_range(drum):
    with pytest.raises(ValueError, match=r"change_time expects a time in \[0, 6\.5\] s or inf.*last beat at 7 s"):
        _context(drum, tempo=60.0, change_time=100.0)
    with pytest.raises(ValueError, match=r"change_time.*\[0, 6\.5\]"):
        _context(drum, tempo=60.0, change_time=6.6)       # its nearest beat (7.x s) is after the last one
    assert _context(drum, tempo=60.0, change_time=6.5).change_time == 6.5
    assert _context(drum, change_time=0.0).change_time == 0.0


def test_a_tempo_that_never_changes_reports_no_new_tempo(drum):
    steady = _context(drum, tempo=90.0, change_time=np.inf)
    assert steady.new_tempo == steady.tempo == 90.0
    assert _context(drum, tempo=90.0, new_tempo=90.0, change_time=np.inf).new_tempo == 90.0
    with pytest.raises(ValueError, match=r"new_tempo.*change_time = inf"):
        _context(drum, tempo=90.0, new_tempo=100.0, change_time=np.inf)


@pytest.mark.parametrize(("options", "error"), [
    ({"tempo": "fast"}, TypeError), ({"tempo": True}, TypeError), ({"tempo": 300.0}, ValueError),
    ({"drum_tilt": (False, False)}, TypeError), ({"drum_position": [0.05, "a"]}, TypeError),
    ({"drum_position": [0.05]}, ValueError), ({"drum_height": None}, TypeError), ({"drum_height": np.nan}, ValueError),
    ({"new_tempo": "x"}, TypeError), ({"new_tempo": 200.0}, ValueError), ({"change_time": None}, TypeError),
    ({"change_time": np.nan}, ValueError), ({"change_time": -1.0}, ValueError), ({"change_time": "soon"}, TypeError),
])
def test_every_drumming_reset_option_is_checked_for_type_and_range_by_name(drum, options, error):
    with pytest.raises(error, match=f"options: {next(iter(options))}"):
        _context(drum, **options)


# ------------------------------------------------------------------ 3, 4. the task registry
def test_registering_the_ids_of_an_unknown_task_or_robot_names_it():
    with pytest.raises(ValueError, match=r"task: expected a registered task, one of \['drum', 'wipe'.*'nosuch'"):
        register_task_ids("nosuch")
    with pytest.raises(ValueError, match=r"robots: .*\['armar3', 'panda'"):
        register_task_ids("drum", robots=("nosuch",))
    with pytest.raises(ValueError, match="robots"):
        register_task_ids("drum", robots="armar3")


class _OtherDrum(DrumTask):
    """A user's drumming task."""


@pytest.mark.parametrize("name", sorted(BUILT_IN))
def test_a_built_in_task_is_replaced_only_when_told(name):
    built_in = TASKS[name]
    with pytest.raises(ValueError, match=f"name: '{name}' is a built-in task.*replace=True"):
        register_task(name, _OtherDrum)
    assert TASKS[name] is built_in
    try:
        register_task(name, _OtherDrum, replace=True)
        assert TASKS[name].factory is _OtherDrum
    finally:
        TASKS[name] = built_in


def test_a_user_task_is_registered_again_alike_and_replaced_only_when_told():
    try:
        register_task("mydrum", DrumTask, id_name="MyDrum")
        register_task("mydrum", DrumTask, id_name="MyDrum")          # the same entry again (another test module)
        with pytest.raises(ValueError, match=r"name: 'mydrum' is a registered task.*replace=True"):
            register_task("mydrum", _OtherDrum, id_name="MyDrum")
        register_task("mydrum", _OtherDrum, id_name="MyDrum", replace=True)
        assert TASKS["mydrum"].factory is _OtherDrum
        with pytest.raises(ValueError, match="versions"):
            register_task("other", DrumTask, versions=(0,))
        with pytest.raises(TypeError, match="name"):
            register_task(3, DrumTask)
    finally:
        TASKS.pop("mydrum", None)


# ------------------------------------------------------------------ 5. the step twins
def test_the_agents_advise_the_episodic_id_for_a_step_twin_and_the_advice_works():
    with pytest.raises(ValueError, match=r"step twin of rdmp_gym/ArmarDrum-v1.*use rdmp_gym/ArmarDrum-v1") as error:
        TaskSpec("rdmp_gym/ArmarDrumStep-v1").make()
    assert "dt=" not in str(error.value)
    env = TaskSpec("rdmp_gym/ArmarDrum-v1").make()
    try:
        assert hasattr(env.unwrapped, "action_to_params")
    finally:
        env.close()


def test_the_step_twin_refuses_to_record_frames_it_never_captures():
    with pytest.raises(ValueError, match="record_frames: the step twin cannot honour it"):
        gym.make("rdmp_gym/ArmarDrumStep-v1", record_frames=True)


# ------------------------------------------------------------------ 6. the checkpoint's fields
@pytest.fixture(scope="module")
def run(tmp_path_factory):
    config = TrainConfig(agent="pi2", updates=1, rollouts=4, seed=3, env_id=TRACKING_ID,
                         env_kwargs={"n_periodic": 8, "n_transient": 8, "duration": 3.0}, start="perturbed",
                         options={"sigma": 0.1})
    return train(config, tmp_path_factory.mktemp("bad") / "run")


@pytest.fixture
def tamper(run):
    """``tamper(field, value)`` writes a checkpoint whose state has ``value`` in ``field`` (its update too, so that
    the file is consistent); the original is put back after the test."""
    original = run.checkpoint_path.read_text()

    def write(field, value):
        document = json.loads(original)
        document["state"][field] = value
        if field == "update":
            document["update"] = value
        run.checkpoint_path.write_text(json.dumps(document))

    yield write
    run.checkpoint_path.write_text(original)


@pytest.mark.parametrize(("field", "value"), [
    ("update", "1"), ("update", 1.5), ("update", True), ("episodes", -4), ("episodes", "4"), ("elapsed", "x"),
    ("elapsed", {"__float__": "inf"}), ("best", 3), ("best", {"eval_return_mean": True}), ("agent", 3),
])
def test_a_checkpoint_field_of_the_wrong_type_is_refused_naming_the_file_and_field(run, tamper, field, value):
    tamper(field, value)
    with pytest.raises(ValueError, match=rf"checkpoint.json: the field '{field}' is .*expected"):
        run.load_checkpoint()


def test_resuming_from_such_a_checkpoint_is_refused(run, tamper):
    tamper("best", {"eval_return_mean": True})
    with pytest.raises(ValueError, match=r"checkpoint.json: the field 'best'"):
        train(None, run.path, resume=True)
