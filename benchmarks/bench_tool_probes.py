"""Probes of the tools on every kind of env: each is a command a new user would run, with what it printed.

A probe passes when the command works and prints what it should (the task's own metrics), or when bad input is
refused with an error that names the argument. The commands run tiny trainings (1-2 updates) from the command line
(``rdmp_gym.agents.cli.main``) and direct calls of the API.

    python benchmarks/bench_tool_probes.py --save      # writes benchmarks/results/tool_probes.json
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import rdmp_gym.envs  # noqa: F401  (registers the ids)
from output import add_save_argument, results_dir
from rdmp_gym.agents.cli import main as cli
from rdmp_gym.envs.blackbox import make_blackbox

TINY = ["--updates", "1", "--rollouts", "2", "--eval-episodes", "1", "--workers", "1"]


def _cli(*argv: str) -> tuple[int, str]:
    """``rdmp-gym ARGV``: (exit status, what it printed on stdout and stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = cli(list(argv))
    return status, out.getvalue() + err.getvalue()


def _train_evaluate(folder: Path, env_id: str, *extra: str) -> dict[str, Any]:
    """Train 1 update on ``env_id`` and evaluate on 2 test contexts; the evaluation's printed table."""
    run = folder / env_id.replace("/", "_")
    status, printed = _cli("train", "--env", env_id, "--out", str(run), *TINY, *extra)
    if status:
        return {"ok": False, "printed": printed.strip().splitlines()[-1]}
    status, printed = _cli("evaluate", str(run), "--episodes", "2", "--workers", "1")
    lines = [line for line in printed.splitlines() if line.strip() and "it/s" not in line and "|" not in line]
    return {"ok": status == 0 and (run / "evaluation.json").exists(), "printed": lines[:4]}


def _refused(call: Callable[[], Any], argument: str) -> dict[str, Any]:
    """Whether ``call()`` raises a ValueError/TypeError whose message names ``argument``."""
    try:
        call()
    except (ValueError, TypeError) as error:
        return {"ok": argument in str(error), "printed": f"{type(error).__name__}: {error}"[:300]}
    return {"ok": False, "printed": "accepted"}


def _drum(**settings: Any) -> Callable[[], Any]:
    return lambda: gym.make("rdmp_gym/ArmarDrum-v1", **settings)


def _drum_reset(**options: Any) -> Callable[[], Any]:
    def call() -> Any:
        env = gym.make("rdmp_gym/ArmarDrum-v1")
        try:
            return env.reset(seed=0, options=options)
        finally:
            env.close()
    return call


def _repeated_options() -> dict[str, Any]:
    from rdmp_gym.agents.run_commands import parse_train

    command = parse_train(["--env", "Hopper-v5", "--out", "x", "--env-option", "p_gains", "5",
                           "--env-option", "ctrl_cost_weight", "0.0", "--reset-option", "a", "1",
                           "--reset-option", "b", "2"])
    kept = {**command.env_kwargs, **(command.reset_options or {})}
    return {"ok": {"p_gains", "ctrl_cost_weight", "a", "b"} <= set(kept), "printed": repr(kept)}


def _loose_env() -> dict[str, Any]:
    """An env as robosuite's GymWrapper gives one: ``metadata = None``, no spec, no time limit."""
    from rdmp_gym.envs.blackbox.wrapper import RhythmicBlackBoxWrapper

    inner = gym.make("Reacher-v5").unwrapped
    inner.metadata = None
    inner.spec = None
    try:
        RhythmicBlackBoxWrapper(inner)
    except ValueError as error:
        advice = str(error)
    wrapper = RhythmicBlackBoxWrapper(inner, duration=1.0)
    wrapper.reset(seed=0)
    reward = wrapper.step(np.zeros(wrapper.action_space.shape, np.float32))[1]
    return {"ok": np.isfinite(reward) and "duration" in advice,
            "printed": f"without duration: {advice[:160]} | with duration=1.0: return {reward:.3f}"}


def _time_limit() -> dict[str, Any]:
    from rdmp_gym.envs.blackbox.wrapper import RhythmicBlackBoxWrapper

    inner = gym.wrappers.TimeLimit(gym.make("Reacher-v5").unwrapped, max_episode_steps=20)
    return _refused(lambda: RhythmicBlackBoxWrapper(inner, duration=5.0), "duration")


def _checkpoint(folder: Path) -> dict[str, Any]:
    run = folder / "checkpoint_run"
    status, printed = _cli("train", "--env", "rdmp_gym/DMPTracking-v0", "--agent", "cmaes", "--out", str(run), *TINY)
    document = json.loads((run / "checkpoint.json").read_text())
    document["state"]["elapsed"] = "x"
    (run / "checkpoint.json").write_text(json.dumps(document))
    status, printed = _cli("train", "--out", str(run), "--resume", "--updates", "2")
    return {"ok": status == 2 and "'elapsed'" in printed, "printed": printed.strip().splitlines()[-1][:300]}


def probes(folder: Path) -> dict[str, dict[str, Any]]:
    """Every probe's outcome: ``{name: {"ok": bool, "printed": ...}}``."""
    from rdmp_gym.envs.registration import register_task_ids
    from rdmp_gym.envs.tasks import register_task

    found = {
        "evaluate on drumming": lambda: _train_evaluate(folder, "rdmp_gym/ArmarDrum-v1", "--agent", "cmaes"),
        "evaluate on a one-actuator env (InvertedPendulum-v5)":
            lambda: _train_evaluate(folder, "InvertedPendulum-v5", "--agent", "cmaes"),
        "evaluate on a wrapped env (Hopper-v5) prints the return":
            lambda: _train_evaluate(folder, "Hopper-v5", "--agent", "cmaes"),
        "train with no option on Walker2d-v5": lambda: _train_evaluate(folder, "Walker2d-v5", "--agent", "cmaes"),
        "drumming features tempo": lambda: _train_evaluate(folder, "rdmp_gym/PandaDrum-v1", "--agent", "cpi2",
                                                           "--options.features", "tempo"),
        "drumming features patch_size refused": lambda: {
            "ok": (result := _cli("train", "--env", "rdmp_gym/ArmarDrum-v1", "--agent", "cpi2", "--out",
                                  str(folder / "patch"), *TINY, "--options.features", "patch_size"))[0] == 2
            and "patch_size" in result[1], "printed": result[1].strip().splitlines()[-1][:300]},
        "repeated --env-option and --reset-option": _repeated_options,
        "a loosely Gymnasium env (metadata None, no spec, no time limit)": _loose_env,
        "duration longer than a TimeLimit": _time_limit,
        "step twin refused with working advice": lambda: {
            "ok": (result := _cli("train", "--env", "rdmp_gym/ArmarDrumStep-v1", "--out", str(folder / "twin"),
                                  *TINY))[0] == 2 and "rdmp_gym/ArmarDrum-v1" in result[1],
            "printed": result[1].strip().splitlines()[-1][:300]},
        "drumming max_jerk_ratio=-1": lambda: _refused(_drum(max_jerk_ratio=-1), "max_jerk_ratio"),
        "drumming rest_speed=-1": lambda: _refused(_drum(rest_speed=-1), "rest_speed"),
        "drumming impulse_band=(0.1,)": lambda: _refused(_drum(impulse_band=(0.1,)), "impulse_band"),
        "drumming reset change_time=100": lambda: _refused(_drum_reset(change_time=100), "change_time"),
        "drumming reset tempo='fast'": lambda: _refused(_drum_reset(tempo="fast"), "tempo"),
        "wrapper duration=nan": lambda: _refused(
            lambda: make_blackbox("Reacher-v5", duration=float("nan")), "duration"),
        "register_task_ids('nosuch')": lambda: _refused(lambda: register_task_ids("nosuch"), "task"),
        "register_task over a built-in name": lambda: _refused(
            lambda: register_task("drum", "rdmp_gym.envs.tasks.drumming:DrumTask", id_name="Other"), "drum"),
        "checkpoint field of the wrong type": lambda: _checkpoint(folder),
    }
    results = {}
    for name, probe in found.items():
        start = time.perf_counter()
        try:
            results[name] = probe()
        except Exception as error:  # a probe that crashes is a failed probe, reported as such
            results[name] = {"ok": False, "printed": f"crashed: {type(error).__name__}: {error}"[:300]}
        results[name]["seconds"] = round(time.perf_counter() - start, 1)
        print(f"{'ok  ' if results[name]['ok'] else 'FAIL'} {name}: {results[name]['printed']}", flush=True)
    return results


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    add_save_argument(parser)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        results = probes(Path(folder))
    passed = sum(result["ok"] for result in results.values())
    print(f"{passed} of {len(results)} probes pass")
    target = results_dir(args.save) / "tool_probes.json"
    target.write_text(json.dumps(results, indent=1) + "\n")
    print(f"wrote {target}")


if __name__ == "__main__":
    main()
