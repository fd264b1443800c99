"""Demonstrations in, DMPs out, and the Gymnasium conventions for one-step episodes: resampling, the frame
check, purely periodic demonstrations, the saved-DMP round trip, the vector-env recipe, videos of one-step
episodes, the human/depth render modes, and housekeeping (registration, SB3 temp folders, outputs)."""

import importlib.util
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from rdmp_gym.agents.tasks import TaskSpec
from rdmp_gym.agents.training import TrainConfig, train
from rdmp_gym.envs import ENV_ID, TRACKING_ID, RecordEpisodeVideo

from rdmp_gym import Demonstration, RhythmicDMP, load_dmp, save_dmp, wiping_demonstration

ROOT = Path(__file__).resolve().parent.parent
SMALL = {"n_periodic": 12, "n_transient": 12, "duration": 3.0}


# ----------------------------------------------------------------------------- demonstrations
def test_from_samples_resamples_uneven_stamps_onto_an_even_grid():
    rng = np.random.default_rng(0)
    t = np.arange(0.0, 6.0, 0.01) + np.r_[0.0, rng.uniform(-3e-3, 3e-3, 599)]
    Y = np.column_stack([np.sin(2 * np.pi * t / 1.5), np.cos(2 * np.pi * t / 1.5)])
    with pytest.raises(ValueError, match="from_samples"):
        Demonstration(t, Y)
    demo = Demonstration.from_samples(t, Y, name="jittery", rate=100.0)
    assert np.allclose(np.diff(demo.t), 0.01) and demo.t[0] == t[0] and demo.t[-1] <= t[-1]
    truth = np.column_stack([np.sin(2 * np.pi * demo.t / 1.5), np.cos(2 * np.pi * demo.t / 1.5)])
    assert np.max(np.abs(demo.Y - truth)) < 2e-4


def test_resample_changes_the_rate_and_keeps_the_signal():
    demo = wiping_demonstration(1, rng=0, noise=0.0)
    fast = demo.resample(250.0)
    assert fast.n_samples == round(demo.duration * 250) + 1 and fast.truth is None
    assert np.allclose(fast.Y[::5][: demo.n_samples // 2], demo.Y[::2][: demo.n_samples // 2], atol=1e-5)
    with pytest.raises(ValueError, match="rate"):
        demo.resample(-1.0)


def test_frame_check_accepts_the_table_frame_and_refuses_millimetres_and_world_coordinates():
    demo = wiping_demonstration(2, rng=0)
    demo.check_frame(centre_dims=(0, 1))
    with pytest.raises(ValueError, match="millimetres"):
        Demonstration(demo.t, demo.Y * 1000.0).check_frame(centre_dims=(0, 1))
    with pytest.raises(ValueError, match="table frame"):
        Demonstration(demo.t, demo.Y + np.array([0.6, 0.0, 0.9])).check_frame(centre_dims=(0, 1))


@pytest.mark.parametrize(("scale", "offset", "message"), [(1000.0, 0.0, "millimetres"), (1.0, 0.9, "table frame")])
def test_env_refuses_a_demonstration_outside_the_workspace_at_make(scale, offset, message):
    demo = wiping_demonstration(1, rng=0)
    bad = Demonstration(demo.t, demo.Y * scale + [0.0, 0.0, offset], name="recording")
    with pytest.raises(ValueError, match=message):
        gym.make(ENV_ID, demonstration=bad)


def test_a_purely_periodic_demonstration_is_refused_with_a_message_about_the_data():
    demo = wiping_demonstration(1, rng=0, noise=0.0)
    late = demo.t >= 3.0
    noise = 3e-4 * np.random.default_rng(0).standard_normal((int(late.sum()), 3))
    periodic = Demonstration(demo.t[late] - 3.0, demo.Y[late] + noise, name="my recording")
    with pytest.raises(ValueError, match=r"periodic from its first samples.*PeriodicDMP") as error:
        RhythmicDMP.fit(periodic)
    assert "my recording" in str(error.value) and "segmentations" not in str(error.value)


def test_a_too_short_demonstration_says_what_to_record():
    demo = wiping_demonstration(1, rng=0)
    short = Demonstration(demo.t[:251], demo.Y[:251])
    with pytest.raises(ValueError, match="record") as error:
        RhythmicDMP.fit(short)
    assert "nan" not in str(error.value)


# ----------------------------------------------------------------------------- saved DMPs
def test_a_saved_refined_dmp_replays_the_refined_episode_without_refitting(tmp_path, monkeypatch):
    env = gym.make(ENV_ID, n_periods=2)
    action = 0.3 * np.random.default_rng(1).uniform(-1, 1, env.action_space.shape).astype(np.float32)
    env.reset(seed=4)
    _, reward, *_, info = env.step(action)
    base = env.unwrapped
    refined = base.policy_dmp(base.action_to_params(action))
    save_dmp(refined, tmp_path / "dmp.json")

    monkeypatch.setattr(RhythmicDMP, "fit", classmethod(lambda *a, **k: pytest.fail("refitted")))
    replay = gym.make(ENV_ID, dmp=str(tmp_path / "dmp.json"), n_periods=2)
    replay.reset(seed=4)
    _, replayed, *_, replay_info = replay.step(np.zeros(replay.action_space.shape, np.float32))
    assert info["valid"] and replay_info["coverage"] == pytest.approx(info["coverage"], abs=1e-12)
    # the same episode: every reward term agrees except smoothness, whose reference (the env's DMP at
    # a = 0, ArmarWipe-v1) is now the refined DMP itself
    terms, replayed_terms = info["reward_terms"], replay_info["reward_terms"]
    assert abs(replayed_terms["smoothness"]) < 1e-9 and terms["smoothness"] < 0.0
    for term in terms:
        if term != "smoothness":
            assert replayed_terms[term] == pytest.approx(terms[term], abs=1e-9), term
    assert replayed == pytest.approx(reward - terms["smoothness"], abs=1e-8)
    with pytest.raises(FileNotFoundError, match="dmp"):
        gym.make(ENV_ID, dmp=str(tmp_path / "missing.json"))


def test_every_run_writes_the_refined_dmp_in_the_core_format(tmp_path):
    config = TrainConfig(agent="pi2", updates=2, rollouts=4, seed=0, env_id=TRACKING_ID,
                         env_kwargs={"n_periodic": 10, "n_transient": 10, "duration": 4.0}, start="perturbed")
    run = train(config, tmp_path / "run")
    saved = load_dmp(run.path / "dmp.json")
    env = config.task.make().unwrapped
    best = json.loads((run.path / "best_params.json").read_text())
    assert np.allclose(saved.get_params(env.groups), best["params"], rtol=0, atol=1e-12)
    assert not np.allclose(saved.get_params(env.groups), env.dmp.get_params(env.groups))


# ----------------------------------------------------------------------------- Gymnasium conventions
def test_vector_env_recipe_same_step_autoreset_gives_a_real_episode_every_step():
    same = gym.make_vec(ENV_ID, num_envs=2, vectorization_mode="sync", n_periods=1,
                        vector_kwargs={"autoreset_mode": gym.vector.AutoresetMode.SAME_STEP})
    same.reset(seed=0)
    zero = np.zeros(same.action_space.shape, np.float32)
    rewards = np.array([same.step(zero)[1] for _ in range(3)])
    assert np.all(rewards != 0.0) and np.all(np.isfinite(rewards))
    default = gym.make_vec(ENV_ID, num_envs=2, vectorization_mode="sync", n_periods=1)
    default.reset(seed=0)
    dummy = np.array([default.step(zero)[1] for _ in range(2)])
    assert np.all(dummy[1] == 0.0)       # NEXT_STEP: every second step is the reset, a dummy reward-0 step
    same.close()
    default.close()


def test_record_episode_video_writes_the_frames_inside_a_one_step_episode(tmp_path):
    import imageio.v3 as iio

    env = RecordEpisodeVideo(gym.make(ENV_ID, render_mode="rgb_array", width=64, height=64, n_periods=0.5,
                                      frame_stride=10), tmp_path, episode_trigger=lambda i: i == 1)
    zero = np.zeros(env.action_space.shape, np.float32)
    for seed in range(2):
        env.reset(seed=seed)
        env.step(zero)
    assert [path.name for path in env.videos] == ["rl-video-episode-1.mp4"]
    frames = list(iio.imiter(env.videos[0]))
    assert len(frames) >= env.unwrapped.n_steps // 10 > 2
    assert frames[0].shape == (64, 64, 3) and np.ptp(np.asarray(frames, dtype=float).mean(axis=(1, 2, 3))) > 0
    env.close()


def test_render_mode_human_says_why_without_a_display(monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    with pytest.raises(ValueError, match=r"render_mode: 'human'.*(display|offscreen)"):
        gym.make(ENV_ID, render_mode="human")


def test_render_mode_human_follows_the_episode_in_the_viewer(monkeypatch):
    import mujoco.viewer

    synced = []

    class FakeHandle:
        def sync(self):
            synced.append(1)

        def close(self):
            synced.append("closed")

    monkeypatch.setattr("rdmp_gym.envs.viewer.display_problem", lambda: None)
    monkeypatch.setattr(mujoco.viewer, "launch_passive", lambda model, data: FakeHandle())
    env = gym.make(ENV_ID, render_mode="human", n_periods=0.5)
    assert not isinstance(env, gym.wrappers.HumanRendering) and env.unwrapped.render_mode == "human"
    env.reset(seed=0)
    env.step(np.zeros(env.action_space.shape, np.float32))
    assert env.render() is None
    env.close()
    assert synced.count(1) >= env.unwrapped.n_steps and synced[-1] == "closed"


def test_depth_array_renders_metric_depth():
    env = gym.make(ENV_ID, render_mode="depth_array", width=64, height=48)
    env.reset(seed=0)
    depth = env.render()
    assert depth.shape == (48, 64) and depth.dtype == np.float32 and np.all(np.isfinite(depth))
    assert 0.3 < depth.min() < 5.0 and np.ptp(depth) > 0.1
    env.close()


# ----------------------------------------------------------------------------- housekeeping
def test_tracking_env_is_registered_by_the_envs_package():
    assert gym.spec(TRACKING_ID).entry_point == "rdmp_gym.envs.tracking:TrackingEnv"


def test_ppo_leaves_no_sb3_folder_in_the_temp_directory(tmp_path, monkeypatch):
    from rdmp_gym.agents.sb3 import PPOAgent

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    task = TaskSpec(TRACKING_ID, {"n_periodic": 8, "n_transient": 8, "duration": 3.0})
    agent = PPOAgent(task, np.zeros(task.make().action_space.shape), rollouts=2, workers=1, seed=0)
    agent.train_update()
    agent.load_state_dict(agent.state_dict())
    agent.train_update()
    agent.close()
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith("SB3-")] == []


def test_examples_and_benchmarks_write_under_runs_unless_asked(tmp_path):
    env = {**os.environ, "MPLBACKEND": "Agg"}
    subprocess.run([sys.executable, str(ROOT / "examples" / "fit_and_reproduce.py")], cwd=tmp_path, env=env,
                   check=True, capture_output=True, timeout=300)
    assert [p.name for p in tmp_path.iterdir()] == ["runs"]
    assert (tmp_path / "runs" / "examples" / "fit_and_reproduce.png").is_file()
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        import output
    finally:
        sys.path.remove(str(ROOT / "benchmarks"))
    assert output.results_dir(save=True) == ROOT / "benchmarks" / "results"
    assert output.SCRATCH.parts[-2:] == ("runs", "benchmarks")
    for script in sorted((ROOT / "benchmarks").glob("bench_*.py")):
        text = script.read_text()
        assert "add_save_argument(parser)" in text and "results_dir(" in text, script.name


def _ppo_config(**options):
    return TrainConfig(agent="ppo", updates=1, rollouts=2, seed=0, env_id=TRACKING_ID,
                       env_kwargs={"n_periodic": 8, "n_transient": 8, "duration": 3.0}, options=options)


def test_ppo_tensorboard_logging_without_the_package_names_the_extra(tmp_path, monkeypatch):
    find_spec = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "tensorboard"
                        else find_spec(name, *a))
    with pytest.raises(ModuleNotFoundError, match=r"rdmp-gym\[tensorboard\]"):
        train(_ppo_config(tensorboard=True), tmp_path / "run")
    assert not (tmp_path / "run").exists()


@pytest.mark.skipif(importlib.util.find_spec("tensorboard") is None, reason="needs the tensorboard extra")
def test_ppo_tensorboard_logging_writes_into_the_run_directory(tmp_path):
    run = train(_ppo_config(tensorboard=True), tmp_path / "run")
    assert list((run.path / "tensorboard").glob("events.out.tfevents.*"))


@pytest.mark.slow
def test_make_run_can_be_run_twice(tmp_path):
    out = tmp_path / "main"
    tiny = ("--updates 1 --rollouts 2 --workers 1 --episodes 1 --env rdmp_gym/DMPTracking-v0 --env-option n_periodic 8 "
            "n_transient 8 duration 3")
    command = ["make", "-s", "-o", ".venv/.installed", "run", f"RUN_OUT={out}", f"RUN_FLAGS={tiny}"]
    first = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert first.returncode == 0, first.stderr[-2000:]
    summary = (out / "summary.json").stat().st_mtime_ns
    second = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert second.returncode == 0, second.stderr[-2000:]
    assert (out / "summary.json").stat().st_mtime_ns > summary
    assert len((out / "train" / "log.jsonl").read_text().splitlines()) == 2    # nothing trained twice


def test_the_comparison_table_leaves_out_gains_a_task_does_not_measure(capsys):
    """A metric some test context has no value of (a path refused before it ran) has no paired gain: "-", not an
    error; a task that reports no success (the tracking env) has no success rate, and no failures are listed."""
    from rdmp_gym.agents.run_commands import _print_comparison

    def scores(returns: list[float], error: list[float | None]) -> dict:
        return {"intervals": {}, "returns": returns, "success": None, "rms_error": error}

    _print_comparison({"has_success": False, "metrics": [{"key": "rms_error", "label": "tracking error (m)"}],
                       "imitation": scores([-1.0, -2.0], [0.01, None]), "trained": scores([-0.5, -1.0], [0.005, 0.01])})
    printed = capsys.readouterr().out
    assert "tracking error (m) -" in printed and "return 0.750 [" in printed
    assert "success" not in printed and "fails on" not in printed


def test_the_comparison_says_which_criteria_each_policy_misses_and_where(capsys):
    from rdmp_gym.agents.run_commands import _print_comparison

    def scores(failures: list[str]) -> dict:
        return {"intervals": {}, "returns": [-1.0] * 3, "success": [not f for f in failures], "coverage": [0.9] * 3,
                "failures": failures}

    _print_comparison({"has_success": True, "metrics": [{"key": "coverage", "label": "coverage"}],
                       "imitation": scores(["coverage+cup", "", "cup"]), "trained": scores(["", "", ""])})
    printed = capsys.readouterr().out
    assert "imitation fails on: coverage 1 (context 0), cup 2 (contexts 0, 2)" in printed
    assert "trained fails on: none" in printed
