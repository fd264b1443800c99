"""The drumming version 2 learners' table from the runs of ``bench_agents.py``: success, timing, jerk, episodes to
validation 0.8 / 0.9, the ear each learner ended with, failures.

``bench_agents.py`` keeps every run's directory (``--run-dir``); this reads them and scores each run's final policy
on the same test contexts (:func:`rdmp_gym.agents.reacting.score_open_loop`: success, the strikes' mean absolute
timing error, jerk, failure causes), reads its validation curve and its policy's ``ear`` value on the test
contexts, and writes ``drum_v2_learners.json`` (``--name``: another name):

    python benchmarks/bench_agents.py --env-id rdmp_gym/ArmarDrum-v2 --agents bbrl random --option bbrl.epsilon=0.2 \\
        --seeds 10 --agent-seeds random=3 --budget 300 --rollouts 10 --test-contexts 50 --val-contexts 10 \\
        --eval-every 3 --workers 1 --run-dir runs/drum_v2_agents_armar --name agents_drum_v2_armar --save
    # the Panda: rdmp_gym/PandaDrum-v2, runs/drum_v2_agents_panda, agents_drum_v2_panda
    python benchmarks/drum_v2_table.py --runs armar3=runs/drum_v2_agents_armar panda=runs/drum_v2_agents_panda --save
"""

from __future__ import annotations

import argparse
import json
import os
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np
import rdmp_gym.envs  # noqa: F401  (registers the ids)
from output import add_save_argument, results_dir
from rdmp_gym.agents.learners import policy_from_state
from rdmp_gym.agents.protocol import context_observations, defined_interval, final_test_seeds
from rdmp_gym.agents.reacting import score_open_loop
from rdmp_gym.agents.runs import RunDirectory
from rdmp_gym.agents.training import load_run_config

THRESHOLDS = (0.8, 0.9)


def _first_reaching(log: list[dict], threshold: float) -> int | None:
    """The episodes after which the validation success first reaches ``threshold`` (None: never)."""
    for row in log:
        if row.get("eval_success") is not None and row["eval_success"] >= threshold:
            return int(row["episodes"])
    return None


def _ear(run: RunDirectory, test: int) -> float:
    """The mean ``ear`` value (action units) of the run's final policy on the test contexts."""
    config = load_run_config(run)
    env = config.task.make()
    seeds = final_test_seeds(test)
    actions = policy_from_state(run.load_checkpoint()["agent"]["learner"],
                                context_observations(env.unwrapped, seeds, config.task.options()))
    index = env.unwrapped.action_slices()["ear"]
    env.close()
    return float(np.mean(np.asarray(actions)[:, index]))


def score_run(folder: Path, test: int) -> dict:
    """One run's row: its final policy on the test contexts and its validation curve."""
    run = RunDirectory(folder)
    scored = score_open_loop(folder, test)
    log = run.read_log()
    return {"run": folder.name, "success": scored["success_rate"], "jerk_ratio": scored["jerk_ratio"],
            "timing_error": scored["metrics"]["mean_abs_timing_error"], "failures": scored["failures"],
            "ear": _ear(run, test), **{f"episodes_to_{t}": _first_reaching(log, t) for t in THRESHOLDS}}


def summarise(rows: list[dict]) -> dict:
    """The IQM and 95 % interval of the learner's runs ``rows``, the runs reaching each threshold, the failures."""
    causes: dict[str, int] = {}
    for row in rows:
        for cause, count in row["failures"].items():
            causes[cause] = causes.get(cause, 0) + count
    table = {key: defined_interval(np.array([row[key] for row in rows], dtype=float))
             for key in ("success", "timing_error", "jerk_ratio", "ear")}
    for threshold in THRESHOLDS:
        reached = [row[f"episodes_to_{threshold}"] for row in rows if row[f"episodes_to_{threshold}"] is not None]
        table[f"episodes_to_{threshold}"] = {"runs": len(reached), "median": float(np.median(reached))
                                             if reached else None}
    return {**table, "failures": causes, "runs": len(rows)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", nargs="+", required=True, metavar="ROBOT=DIR")
    parser.add_argument("--test", type=int, default=50)
    parser.add_argument("--name", default="drum_v2_learners", help="output name (results/<name>.json)")
    add_save_argument(parser)
    args = parser.parse_args()
    results = {}
    for pair in args.runs:
        robot, _, folder = pair.partition("=")
        by_agent: dict[str, list[dict]] = {}
        for run in sorted(Path(folder).iterdir()):
            if (run / "checkpoint.json").exists():
                by_agent.setdefault(run.name.rsplit("-", 1)[0], []).append(score_run(run, args.test))
        results[robot] = {agent: {"summary": summarise(rows), "runs": rows} for agent, rows in by_agent.items()}
        for agent, entry in results[robot].items():
            row = entry["summary"]
            timing = "-" if row["timing_error"] is None else f"{1000 * row['timing_error']['estimate']:.1f} ms"
            jerk = "-" if row["jerk_ratio"] is None else f"{row['jerk_ratio']['estimate']:.2f}"
            print(f"{robot} {agent} ({row['runs']} runs): success {row['success']['estimate']:.3f} "
                  f"[{row['success']['low']:.3f}, {row['success']['high']:.3f}], timing {timing}, jerk {jerk}, ear "
                  f"{row['ear']['estimate']:.2f}, validation 0.8 in {row['episodes_to_0.8']}, 0.9 in "
                  f"{row['episodes_to_0.9']}, failures {row['failures']}")
    (results_dir(args.save) / f"{args.name}.json").write_text(json.dumps({"test": args.test, "robots": results},
                                                                            indent=1))


if __name__ == "__main__":
    main()
