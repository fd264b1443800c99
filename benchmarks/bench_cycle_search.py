"""Learners on a task's cycle-level face: test success, episodes to validation 0.8 / 0.9, jerk, failure causes.

``--agent cycle`` (default) is the cycle-by-cycle search (:func:`rdmp_gym.agents.cycle_training.train_cycle_search`),
``--agent reacting`` the reacting learner (:func:`rdmp_gym.agents.reacting.train_reacting`: an open-loop stage, then
the cycles' changes of its policy; its open-loop stage's run in ``RUN_DIR/seed_<n>/open_loop``, continued or reused
where it exists),
``--agent sac`` / ``ppo`` stable-baselines3 on the same face (:func:`rdmp_gym.agents.cycle_sb3.train_cycle_sb3`).

    python benchmarks/bench_cycle_search.py --env rdmp_gym/ArmarWipe-v3 --seeds 0-9 --run-dir runs/cycle_armar
    python benchmarks/bench_cycle_search.py --env rdmp_gym/ArmarWipe-v3 --seeds 0-9 --run-dir runs/cycle_armar \\
        --gather benchmarks/results/cycle_search_armar_wipe_v3.json

Each seed's run is written to ``RUN_DIR/seed_<n>.json`` as it finishes, and a seed whose file exists is skipped, so
an interrupted benchmark continues where it stopped (two processes with different ``--seeds`` may share a run
directory). ``--random-returns`` runs the control that sees standard-normal costs. ``--gather NAME`` prints the
table over the seeds found and writes it as NAME (in ``benchmarks/results/`` with ``--save``, else under
``runs/benchmarks/``). Every run uses the test contexts of
:func:`rdmp_gym.agents.protocol.final_test_seeds` (never used in training or selection) and the validation contexts
for the curve and the choice of the best policy.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
from output import add_save_argument, results_dir
from rdmp_gym.agents.cycle_training import CycleRun, failure_counts, summarise, train_cycle_search
from rdmp_gym.agents.learners.cycle_search import CycleSearchConfig


def _seeds(text: str) -> list[int]:
    """``"0-9"`` or ``"0,3,5"`` -> the seeds."""
    if "-" in text:
        first, last = text.split("-")
        return list(range(int(first), int(last) + 1))
    return [int(part) for part in text.split(",")]


def _settings(default: CycleSearchConfig, changes: list[str]) -> CycleSearchConfig:
    """``default`` with the ``KEY=VALUE`` changes of ``--set`` (VALUE read as JSON)."""
    values = default.to_dict()
    for change in changes:
        key, _, value = change.partition("=")
        values[key] = json.loads(value)
    return CycleSearchConfig.from_dict(values)


def _run_seed(args: argparse.Namespace, seed: int, path: Path) -> None:
    start = time.perf_counter()

    def progress(episodes: int, row: dict[str, float]) -> None:
        print(f"  seed {seed}: {episodes:5d} episodes  validation success {row['validation_success']:.2f}  "
              f"return {row['validation_return']:.3f}  sigma {row.get('sigma', float('nan')):.3f}  "
              f"failures {row.get('validation_failures', {})}  "
              f"{time.perf_counter() - start:.0f} s", flush=True)

    if args.agent == "cycle":
        run = train_cycle_search(args.env, episodes=args.episodes, rollouts=args.rollouts or 16, seed=seed,
                                 workers=args.workers, config=_settings(CycleSearchConfig(), args.set),
                                 validation=args.validation,
                                 test=args.test, random_returns=args.random_returns, progress=progress)
    elif args.agent == "reacting":
        from rdmp_gym.agents.reacting import RESIDUAL, train_reacting

        run = train_reacting(args.env, args.run_dir / f"seed_{seed}", episodes=args.episodes,
                             open_loop=args.open_loop, seed=seed, workers=args.workers, rollouts=args.rollouts or 20,
                             validation=args.validation, test=args.test, residual=_settings(RESIDUAL, args.set),
                             progress=progress)
    else:
        from rdmp_gym.agents.cycle_sb3 import train_cycle_sb3

        run = train_cycle_sb3(args.env, args.agent, episodes=args.episodes, seed=seed, rollouts=args.rollouts or 16,
                              validation=args.validation, test=args.test, progress=progress)
    run.save(path)
    causes = failure_counts(run.test["failures"])
    print(f"seed {seed}: test success {run.test['success_rate']:.2f} (best after {run.best_episodes} episodes), "
          f"failures {causes}, {run.wall_seconds:.0f} s", flush=True)


def _gather(run_dir: Path, out: Path) -> None:
    runs = [CycleRun(**json.loads(path.read_text())) for path in sorted(run_dir.glob("seed_*.json"))]
    if not runs:
        raise SystemExit(f"--gather: no seed_*.json in {run_dir}")
    table = summarise(runs)
    stages = {run.seed: run_dir / f"seed_{run.seed}" / "open_loop" for run in runs}
    if all(stage.is_dir() for stage in stages.values()):            # the reacting learner: its start, paired
        from rdmp_gym.agents.reacting import score_open_loop

        table["open_loop_test"] = {seed: score_open_loop(stage, len(runs[0].test["seeds"]))
                                   for seed, stage in stages.items()}
    causes = failure_counts([entry for run in runs for entry in run.test["failures"]])
    table.update({"env": runs[0].env_id, "seeds": [run.seed for run in runs], "failure_causes": causes,
                  "config": runs[0].config, "wall_seconds": [run.wall_seconds for run in runs],
                  "curves": {run.seed: run.curve for run in runs},
                  "test_success_per_seed": [run.test["success_rate"] for run in runs],
                  "test_metrics": {key: float(np.mean([np.nanmean(run.test["metrics"][key]) for run in runs]))
                                   for key in runs[0].test["metrics"]}})
    success = table["test_success"]
    print(f"{table['env']}: {len(runs)} seeds, test success IQM {success['estimate']:.3f} "
          f"[{success['low']:.3f}, {success['high']:.3f}], jerk ratio {table['jerk_ratio']:.2f}, "
          f"validation 0.8 after {table['episodes_to_0.8']}, 0.9 after {table['episodes_to_0.9']}, "
          f"failures {causes}")
    out.write_text(json.dumps(table, indent=1))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", default="rdmp_gym/ArmarWipe-v3")
    parser.add_argument("--agent", choices=("cycle", "reacting", "sac", "ppo"), default="cycle")
    parser.add_argument("--seeds", default="0-9", type=_seeds)
    parser.add_argument("--episodes", type=int, default=1000)
    parser.add_argument("--rollouts", type=int, default=None, help="episodes per update (default: 16; reacting 20)")
    parser.add_argument("--open-loop", type=float, default=0.6,
                        help="reacting: the share of the episodes for the open-loop stage")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--validation", type=int, default=20)
    parser.add_argument("--test", type=int, default=50)
    parser.add_argument("--random-returns", action="store_true")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="a setting of the cycle search (reacting: of its reacting stage), e.g. pooled=true")
    parser.add_argument("--run-dir", type=Path, required=True)
    parser.add_argument("--gather", default=None, metavar="NAME",
                        help="print the table over the seeds in --run-dir and write it as the JSON file NAME")
    add_save_argument(parser)
    args = parser.parse_args()
    if args.agent in ("sac", "ppo") and (args.set or args.random_returns):
        parser.error(f"--set and --random-returns are settings of the cycle search; --agent {args.agent} takes "
                     "neither")
    if args.gather is not None:
        _gather(args.run_dir, results_dir(args.save) / args.gather)
        return
    for seed in args.seeds:
        path = args.run_dir / f"seed_{seed}.json"
        if path.exists():
            print(f"seed {seed}: done ({path})")
            continue
        _run_seed(args, seed, path)


if __name__ == "__main__":
    main()
