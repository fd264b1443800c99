"""Where along the path the trained policies fail: the first control step each failure cause is charged.

For every run directory kept by ``bench_agents.py --run-dir DIR`` (``DIR/<label>-<seed>``), the final policy
on the test contexts of the agents' protocol (``--test-contexts``, the benchmark's 50). Per failed context:
its causes and, for each cause that the per-step cost charges at a moment, the first such control step and
the part of the path it falls in: ``approach`` (the transient, from the start to the patch) or ``wiping``
cycle ``k`` (1 = the first cycle of the periodic pattern); the cup's place (on the start-to-patch line, before
the patch centre, or elsewhere). Coverage and force are judged over the whole episode: no moment.

    python benchmarks/bench_agents.py --agents plain_prior=cpi2 ... --only-seeds 0 2 --run-dir DIR
    python benchmarks/bench_failure_times.py --run-dir DIR [--test-contexts 50] [--name NAME] [--save]
"""

from __future__ import annotations

import argparse
import json
import os
from collections import Counter
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np
import rdmp_gym.envs  # noqa: F401  (registers the envs)
from bench_cup_plateau import on_approach
from output import add_save_argument, results_dir
from rdmp_gym.agents.protocol import context_observations, final_test_seeds
from rdmp_gym.agents.report import trained_actions
from rdmp_gym.agents.runs import RunDirectory
from rdmp_gym.agents.training import load_run_config

#: the per-step cost term that charges each failure cause at the moment it happens
CAUSE_TERMS = {"cup": "obstacle", "joint acceleration": "joint_accel", "self-collision": "self_collision",
               "arm collision": "arm_collision", "joint limit": "joint_limit"}


def path_part(step: int, env) -> str:
    """``"approach"`` for a control step in the transient, else ``"wiping k"`` (k: the periodic cycle, from 1)."""
    periodic = env.task.periodic
    if not periodic[step]:
        return "approach"
    since = env.times[step] - env.times[np.argmax(periodic)]
    return f"wiping {int(since // env.dmp.period) + 1}"


def failure_moments(info: dict, env) -> dict[str, dict]:
    """``{cause: {"step", "part"}}`` for each failure cause of an episode's ``info`` that its cost charges at a
    moment (``step`` None for the causes judged over the whole episode)."""
    moments = {}
    for cause in info["failure_causes"]:
        trace = info["cost_terms"].get(CAUSE_TERMS.get(cause, ""))
        charged = np.flatnonzero(trace) if trace is not None else np.array([], dtype=int)
        step = int(charged[0]) if charged.size else None
        moments[cause] = {"step": step, "part": path_part(step, env) if step is not None else "whole episode"}
    return moments


def run_failures(run_dir: Path, seeds: np.ndarray) -> dict:
    """The final policy of the run in ``run_dir`` on the contexts ``seeds [E]``: its failed contexts."""
    run = RunDirectory(run_dir)
    config = load_run_config(run)
    env = config.task.make()
    observations = context_observations(env, seeds)
    actions = trained_actions(run, config, "last", observations, int(np.prod(env.action_space.shape)))
    approach = on_approach(observations)
    failed = []
    for index, (seed, action) in enumerate(zip(seeds, actions, strict=True)):
        env.reset(seed=int(seed))
        _, _, _, _, info = env.step(action.astype(np.float32))
        if not info["is_success"]:
            failed.append({"index": index, "seed": int(seed), "valid": bool(info["valid"]),
                           "cup_on_approach": bool(approach[index]), "causes": failure_moments(info, env.unwrapped)})
    env.close()
    return {"run": run_dir.name, "env_id": config.env_id, "contexts": len(seeds), "failed": failed}


def tally(runs: list[dict]) -> Counter:
    """``{(cause, part, cup place): count}`` over every failed context of ``runs``."""
    counts: Counter = Counter()
    for run in runs:
        for context in run["failed"]:
            place = "cup on approach" if context["cup_on_approach"] else "cup elsewhere"
            for cause, moment in context["causes"].items():
                counts[(cause, moment["part"].split(" ")[0] if moment["step"] is not None else moment["part"],
                        place if cause == "cup" else "")] += 1
    return counts


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--run-dir", required=True, help="the run directories of bench_agents.py --run-dir")
    parser.add_argument("--test-contexts", type=int, default=50, help="test contexts of the protocol")
    parser.add_argument("--name", default="failure_times", help="output name (results/<name>.json)")
    add_save_argument(parser)
    args = parser.parse_args()
    folders = sorted(path for path in Path(args.run_dir).iterdir() if (path / "config.json").is_file())
    if not folders:
        raise SystemExit(f"--run-dir: no run directories (with config.json) in {args.run_dir}")
    seeds = final_test_seeds(args.test_contexts)
    runs = [run_failures(folder, seeds) for folder in folders]
    for run in runs:
        print(f"{run['run']} ({run['env_id']}): {len(run['failed'])} of {run['contexts']} test contexts failed")
        for context in run["failed"]:
            moments = ", ".join(f"{cause} @{m['step']} ({m['part']})" for cause, m in context["causes"].items())
            print(f"  context {context['index']:2d}{' cup on approach' if context['cup_on_approach'] else ''}: "
                  f"{moments}")
    print("cause, part of the path, cup: count")
    for (cause, part, place), count in sorted(tally(runs).items(), key=lambda item: -item[1]):
        print(f"  {cause:20s} {part:14s} {place:16s} {count}")
    path = results_dir(args.save) / f"{args.name}.json"
    path.write_text(json.dumps({"test_contexts": args.test_contexts, "runs": runs}, indent=1) + "\n")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
