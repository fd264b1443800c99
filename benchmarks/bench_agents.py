"""Benchmark the learners on the wiping task: the same episode budget for PI², PI^BB, CMA-ES and PPO.

For every agent, start (the imitation, and a "shrunk" start whose DMP weights are scaled by 0.7) and
seed, a run of ``budget / rollouts`` updates; after every update the policy is evaluated on fixed
contexts (``--eval-contexts`` per seed, the same for every agent). Contexts: ``random`` (the env's
default, a new table/patch/start per update, shared by that update's rollouts) or ``fixed`` (one
context per seed for training and evaluation).

Writes ``benchmarks/results/agents.json`` (settings, curves, summary) and ``agents.png``, and prints
the table. Target checked: coverage >= 0.95 with force in band >= 0.9 (policy evaluation).

    python benchmarks/bench_agents.py                     # the full benchmark (about 20-40 min on 2 cores)
    python benchmarks/bench_agents.py --seeds 1 --budget 60 --agents pi2 cmaes   # a quick look
    python benchmarks/bench_agents.py --backend ray      # every run a Ray task (RAY_ADDRESS: a cluster)
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import tempfile
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from output import add_save_argument, results_dir
from rdmp_gym.agents.tasks import WIPE_ID, TaskSpec
from rdmp_gym.agents.training import TrainConfig, train
from tqdm import tqdm

import rdmp_gym  # noqa: F401  (registers the env)

COVERAGE_TARGET, FORCE_TARGET = 0.95, 0.90


def _parse() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--agents", nargs="+", default=["pi2", "pibb", "cmaes", "ppo"])
    parser.add_argument("--starts", nargs="+", default=["imitation", "shrunk"])
    parser.add_argument("--seeds", type=int, default=3, help="seeds 0..n-1")
    parser.add_argument("--budget", type=int, default=300, help="training episodes per run")
    parser.add_argument("--rollouts", type=int, default=10, help="episodes per update")
    parser.add_argument("--contexts", choices=("random", "fixed"), default="random")
    parser.add_argument("--eval-contexts", type=int, default=6, help="evaluation contexts (random mode)")
    parser.add_argument("--workers", type=int, default=2, help="processes per run (local backend)")
    parser.add_argument("--backend", choices=("local", "ray"), default="local",
                        help="ray: the runs (agent x start x seed) are Ray tasks of one CPU each, each run on "
                             "1 worker; the same result files")
    parser.add_argument("--ray-address", default=None, help="Ray cluster (default $RAY_ADDRESS, else a local one)")
    parser.add_argument("--option", action="append", default=[], metavar="AGENT.KEY=VALUE",
                        help="override a learner setting, e.g. pi2.sigma=0.5 (repeatable)")
    parser.add_argument("--env-option", action="append", default=[], metavar="KEY=VALUE",
                        help="a gym.make keyword (default: the env's defaults)")
    parser.add_argument("--name", default="agents", help="output name (results/<name>.json, .png)")
    parser.add_argument("--replot", action="store_true", help="redraw the figure and table from results/<name>.json")
    add_save_argument(parser)
    return parser.parse_args()


def _value(text: str) -> object:
    try:
        return json.loads(text)
    except json.JSONDecodeError:
        return text


def _options(args: argparse.Namespace) -> dict[str, dict]:
    options: dict[str, dict] = {agent: {} for agent in args.agents}
    for item in args.option:
        key, _, value = item.partition("=")
        agent, _, name = key.partition(".")
        options.setdefault(agent, {})[name] = _value(value)
    return options


def _first_reaching(records: list[dict]) -> int | None:
    for record in records:
        if (record["eval_coverage"] or 0) >= COVERAGE_TARGET and (record["eval_force_in_band"] or 0) >= FORCE_TARGET:
            return int(record["episodes"])
    return None


def _run(agent: str, start: str, seed: int, args: argparse.Namespace, env_kwargs: dict, options: dict,
         scratch: Path) -> dict:
    reset_options = None
    eval_episodes = args.eval_contexts
    if args.contexts == "fixed":
        env = TaskSpec(WIPE_ID, env_kwargs).make()          # (also registers the env in a Ray worker)
        reset_options = {"context": env.reset(seed=seed)[1]["context"].tolist()}
        env.close()
        eval_episodes = 1
    config = TrainConfig(agent=agent, env_id=WIPE_ID, updates=args.budget // args.rollouts, rollouts=args.rollouts,
                         seed=seed, workers=args.workers, env_kwargs=env_kwargs, reset_options=reset_options,
                         options=options, start=start, perturbation=0.3, eval_episodes=eval_episodes)
    began = time.perf_counter()
    run = train(config, scratch / f"{agent}-{start}-{seed}")
    records = run.read_log()
    return {"agent": agent, "start": start, "seed": seed, "seconds": round(time.perf_counter() - began, 1),
            "options": options, "episodes_to_target": _first_reaching(records),
            "curve": [{key: record.get(key) for key in ("update", "episodes", "eval_return_mean", "eval_coverage",
                                                        "eval_force_in_band", "return_mean", "coverage",
                                                        "force_in_band", "valid", "exploration")}
                      for record in records]}


def _run_on_ray(jobs: list[tuple[str, str, int]], args: argparse.Namespace, env_kwargs: dict,
                options: dict[str, dict], scratch: Path) -> list[dict]:
    """Every run as a Ray task (one CPU, one worker inside); results in the order of ``jobs``."""
    from rdmp_gym.agents.ray_backend import import_ray, init_ray

    ray = import_ray()
    owns = init_ray(os.cpu_count() or 1, args.ray_address)
    remote = ray.remote(num_cpus=1)(_run)
    serial = argparse.Namespace(**{**vars(args), "workers": 1})
    try:
        pending = [remote.remote(agent, start, seed, serial, env_kwargs, options.get(agent, {}), scratch)
                   for agent, start, seed in jobs]
        with tqdm(total=len(pending), desc="runs (ray)", unit="run") as bar:
            for ref in pending:
                ray.wait([ref], num_returns=1)
                bar.update(1)
        return ray.get(pending)
    finally:
        if owns:
            ray.shutdown()


def _summary(runs: list[dict], agents: list[str], starts: list[str]) -> list[dict]:
    rows = []
    for start in starts:
        for agent in agents:
            group = [r for r in runs if r["agent"] == agent and r["start"] == start]
            if not group:
                continue
            first, last = (np.array([[r["curve"][i][k] for k in ("eval_return_mean", "eval_coverage",
                                                                  "eval_force_in_band")] for r in group], dtype=float)
                           for i in (0, -1))
            best_cov = np.array([max(c["eval_coverage"] for c in r["curve"]) for r in group])
            reached = [r["episodes_to_target"] for r in group if r["episodes_to_target"] is not None]
            rows.append({"start": start, "agent": agent, "seeds": len(group),
                         "return_0": float(first[:, 0].mean()), "return": float(last[:, 0].mean()),
                         "return_std": float(last[:, 0].std()), "coverage_0": float(first[:, 1].mean()),
                         "coverage": float(last[:, 1].mean()), "coverage_std": float(last[:, 1].std()),
                         "force_in_band": float(last[:, 2].mean()), "best_coverage": float(best_cov.mean()),
                         "reached": len(reached),
                         "episodes_to_target": float(np.median(reached)) if reached else None,
                         "seconds": float(np.mean([r["seconds"] for r in group]))})
    return rows


def _print(rows: list[dict], budget: int) -> None:
    header = (f"{'start':>9} {'agent':>6} {'return 0->end':>17} {'coverage 0->end':>19} {'force in band':>13} "
              f"{'best cov':>8} {'target reached':>14} {'median ep.':>10} {'s/run':>6}")
    print(header)
    for r in rows:
        print(f"{r['start']:>9} {r['agent']:>6} {r['return_0']:7.3f} -> {r['return']:.3f}±{r['return_std']:.3f} "
              f"{r['coverage_0']:7.3f} -> {r['coverage']:.3f}±{r['coverage_std']:.3f} {r['force_in_band']:13.3f} "
              f"{r['best_coverage']:8.3f} {r['reached']:>9}/{r['seeds']:<4} "
              f"{'-' if r['episodes_to_target'] is None else int(r['episodes_to_target']):>10} {r['seconds']:6.0f}")
    print(f"(policy evaluated after each update; budget {budget} training episodes; target coverage >= "
          f"{COVERAGE_TARGET} and force in band >= {FORCE_TARGET})")


def _plot(runs: list[dict], agents: list[str], starts: list[str], path: Path, title: str) -> None:
    keys = [("eval_return_mean", "return"), ("eval_coverage", "coverage"), ("eval_force_in_band", "force in band")]
    figure, axes = plt.subplots(len(starts), 3, figsize=(13, 3.6 * len(starts)), squeeze=False)
    for row, start in enumerate(starts):
        for col, (key, label) in enumerate(keys):
            axis = axes[row][col]
            shown: list[np.ndarray] = []
            for index, agent in enumerate(agents):
                group = [r for r in runs if r["agent"] == agent and r["start"] == start]
                if not group:
                    continue
                episodes = np.array([c["episodes"] for c in group[0]["curve"]])
                values = np.array([[c[key] for c in r["curve"]] for r in group], dtype=float)
                axis.plot(episodes, np.median(values, axis=0), color=f"C{index}", label=agent)
                axis.fill_between(episodes, values.min(axis=0), values.max(axis=0), color=f"C{index}", alpha=0.12)
                shown.append(np.median(values, axis=0))
            if key == "eval_coverage":
                axis.axhline(COVERAGE_TARGET, color="k", ls=":", lw=0.8)
            if key == "eval_force_in_band":
                axis.axhline(FORCE_TARGET, color="k", ls=":", lw=0.8)
            low, high = np.min(shown), np.max(shown)      # frame the medians; a rare invalid episode dips below
            axis.set_ylim(low - 0.15 * (high - low) - 1e-3, high + 0.15 * (high - low) + 1e-3)
            axis.set_title(f"{start} start: {label} (median, min-max over seeds)", fontsize=9)
            axis.set_xlabel("training episodes")
            axis.grid(alpha=0.3)
        axes[row][0].legend(fontsize=8)
    figure.suptitle(title)
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def main() -> None:
    import torch

    torch.set_num_threads(1)
    args = _parse()
    RESULTS = results_dir(args.save)
    if args.replot:
        document = json.loads((RESULTS / f"{args.name}.json").read_text())
        settings = document["settings"]
        _print(document["summary"], settings["budget"])
        _plot(document["runs"], settings["agents"], settings["starts"], RESULTS / f"{args.name}.png",
              f"{settings['contexts']} contexts, {settings['budget']} episodes, {settings['seeds']} seed(s)")
        return
    env_kwargs = {key: _value(value) for key, value in (item.partition("=")[::2] for item in args.env_option)}
    options = _options(args)
    scratch = Path(tempfile.mkdtemp(prefix="bench_agents_"))
    jobs = [(agent, start, seed) for start in args.starts for agent in args.agents for seed in range(args.seeds)]
    runs = []
    try:
        if args.backend == "ray":
            runs = _run_on_ray(jobs, args, env_kwargs, options, scratch)
        else:
            for agent, start, seed in tqdm(jobs, desc="runs", unit="run"):
                runs.append(_run(agent, start, seed, args, env_kwargs, options.get(agent, {}), scratch))
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    rows = _summary(runs, args.agents, args.starts)
    _print(rows, args.budget)
    RESULTS.mkdir(parents=True, exist_ok=True)
    settings = {key: value for key, value in vars(args).items() if key not in ("option", "env_option")}
    settings.update({"env_kwargs": env_kwargs, "options": options, "perturbation": 0.3, "cpus": os.cpu_count()})
    document = {"settings": settings, "targets": {"coverage": COVERAGE_TARGET, "force_in_band": FORCE_TARGET},
                "summary": rows, "runs": runs}
    (RESULTS / f"{args.name}.json").write_text(json.dumps(document, indent=1) + "\n")
    _plot(runs, args.agents, args.starts, RESULTS / f"{args.name}.png",
          f"{args.contexts} contexts, {args.budget} episodes, {args.seeds} seed(s)")
    print(f"wrote {RESULTS / (args.name + '.json')} and {args.name}.png")


if __name__ == "__main__":
    main()
