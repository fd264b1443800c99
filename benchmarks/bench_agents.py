"""Benchmark the learners on the wiping task under the evaluation protocol of ``rdmp_gym.agents.protocol``.

For every agent and seed: one training run of ``budget`` episodes (``budget / rollouts`` updates) on
random training contexts (reset seeds in ``[0, 2**30)``), its policy evaluated every ``eval_every``
updates on the validation contexts (the held-out learning curves), then the **final** policy (never a
"best") evaluated once on the test contexts, which no run trains or selects on. Beside the learners,
every table shows the imitation (``a = 0``), the obstacle-coupling baseline (``coupling``: the imitation
with the online lift over the cup of ``benchmarks/obstacle_baseline.py``; no learning), the amplitude-only
search (``amplitude``: one θ over the 3 amplitude factors) and the random-return control (``random``:
contextual REPS fed random returns).

Per agent: the interquartile mean over seeds of each seed's test-context mean, with a 95 % percentile
bootstrap interval over seeds (success rate, coverage, path jerk relative to the imitation's, return),
and the training episodes until the validation success rate first reaches 90 %. The no-learning rows
(imitation, coupling) are deterministic policies: their intervals are over the test contexts.

Writes ``benchmarks/results/<name>.json`` (settings, per-run curves and per-context test scores, summary)
and ``<name>.png``, and prints the table.

    # the full protocol (10 seeds x 8 agents x 1000 episodes; several hours on 2 cores):
    python benchmarks/bench_agents.py
    # the committed runs on ArmarWipe-v1 (the default env, cup on): results/agents.json (36 min on 2 cores)
    # and results/agents_rl_cmaes.json:
    python benchmarks/bench_agents.py --agents cpi2 amplitude random cpibb creps --seeds 10 --budget 500 \\
        --rollouts 10 --val-contexts 6 --eval-every 10 --save
    python benchmarks/bench_agents.py --agents cmaes ppo --seeds 3 --budget 500 --rollouts 10 --val-contexts 6 \\
        --eval-every 10 --name agents_rl_cmaes --save
    # every run a Ray task of one CPU (RAY_ADDRESS or --ray-address: a cluster); the same result files:
    python benchmarks/bench_agents.py --backend ray
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
import rdmp_gym.envs  # noqa: F401  (registers the env)
from field_report import episodes_to
from field_report import write as write_field_report
from output import SCRATCH, add_save_argument, results_dir
from rdmp_gym.agents.pool import Evaluator
from rdmp_gym.agents.protocol import (
    context_observations,
    evaluate_actions,
    final_test_seeds,
    interval,
    path_jerk,
)
from rdmp_gym.agents.report import trained_actions
from rdmp_gym.agents.runs import RunDirectory
from rdmp_gym.agents.tasks import WIPE_ID, TaskSpec
from rdmp_gym.agents.training import TrainConfig, train
from tqdm import tqdm

SUCCESS_TARGET = 0.9
METRICS = ("success", "coverage", "jerk_ratio", "returns")


def _parse() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--agents", nargs="+",
                        default=["creps", "cpibb", "cpi2", "cmaes", "ppo", "amplitude", "random"],
                        help="learners, or LABEL=LEARNER to run one learner under a second name with its own "
                             "--option LABEL.KEY=VALUE settings")
    parser.add_argument("--seeds", type=int, default=10, help="seeds 0..n-1 per agent")
    parser.add_argument("--agent-seeds", action="append", default=[], metavar="LABEL=N",
                        help="seeds 0..N-1 for one agent instead of --seeds (e.g. fewer for a control; repeatable)")
    parser.add_argument("--only-seeds", type=int, nargs=2, metavar=("FIRST", "STOP"), default=None,
                        help="run only the seeds FIRST..STOP-1 and cache them, writing no table (to share the runs "
                             "of one table between processes; a later call without it gathers the cached runs)")
    parser.add_argument("--budget", type=int, default=1000, help="training episodes per run")
    parser.add_argument("--rollouts", type=int, default=20, help="episodes per update")
    parser.add_argument("--test-contexts", type=int, default=20, help="test contexts (final policy)")
    parser.add_argument("--val-contexts", type=int, default=10, help="validation contexts (learning curves)")
    parser.add_argument("--eval-every", type=int, default=5, help="updates between validation evaluations")
    parser.add_argument("--stratified-validation", action="store_true",
                        help="validation contexts spread evenly over the kinds of context the env names")
    parser.add_argument("--workers", type=int, default=2, help="processes per run (local backend)")
    parser.add_argument("--backend", choices=("local", "ray"), default="local",
                        help="ray: the runs (agent x seed) are Ray tasks of one CPU each, each run on 1 worker; "
                             "the same result files")
    parser.add_argument("--ray-address", default=None, help="Ray cluster (default $RAY_ADDRESS, else a local one)")
    parser.add_argument("--env-id", default=WIPE_ID)
    parser.add_argument("--option", action="append", default=[], metavar="AGENT.KEY=VALUE",
                        help="override a learner setting, e.g. creps.epsilon=1.0 (repeatable)")
    parser.add_argument("--env-option", action="append", default=[], metavar="KEY=VALUE",
                        help="a gym.make keyword (default: the env's defaults)")
    parser.add_argument("--name", default="agents", help="output name (results/<name>.json, .png)")
    parser.add_argument("--run-dir", default=None, metavar="DIR",
                        help="keep every run's directory under DIR (default: a temporary folder, removed at the end); "
                             "a finished run found there is resumed (nothing left to train) and tested again, so "
                             "that another --test-contexts or a longer --budget does not train it from the start")
    parser.add_argument("--fresh", action="store_true",
                        help="ignore the runs cached by an earlier, interrupted call (default: reuse them)")
    parser.add_argument("--reuse", action="append", default=[], metavar="RESULTS.json",
                        help="an earlier results file (e.g. the committed one) whose runs stand for runs of this "
                             "call that match it in every setting (repeatable; local backend; also with --fresh)")
    parser.add_argument("--replot", action="store_true", help="redraw the figure and table from results/<name>.json")
    parser.add_argument("--markdown", action="store_true",
                        help="also print the table in Markdown, with the episodes to 0.5 / 0.8 / 0.9 validation "
                             "success")
    parser.add_argument("--update-baselines", action="store_true",
                        help="re-evaluate the no-learning rows (imitation, coupling) into results/<name>.json, "
                             "keeping its runs")
    add_save_argument(parser)
    return parser.parse_args()


def _value(text: str) -> object:
    try:
        return json.loads(text)
    except json.JSONDecodeError:
        return text


def _labels(agents: list[str]) -> dict[str, str]:
    """``{label: learner}`` from ``--agents`` items ``learner`` or ``label=learner`` (one learner, two settings)."""
    pairs = [item.partition("=")[::2] if "=" in item else (item, item) for item in agents]
    labels = dict(pairs)
    if len(labels) != len(pairs):
        raise SystemExit(f"--agents: every label must be unique, got {agents}")
    return labels


def _options(args: argparse.Namespace) -> dict[str, dict]:
    options: dict[str, dict] = {label: {} for label in _labels(args.agents)}
    for item in args.option:
        key, _, value = item.partition("=")
        agent, _, name = key.partition(".")
        options.setdefault(agent, {})[name] = _value(value)
    return options


def _seed_counts(args: argparse.Namespace, labels: dict[str, str]) -> dict[str, int]:
    """``{label: number of seeds}``: ``--seeds`` unless ``--agent-seeds LABEL=N`` says otherwise."""
    counts = dict.fromkeys(labels, args.seeds)
    for item in args.agent_seeds:
        label, _, count = item.partition("=")
        if label not in labels or not count.isdigit() or int(count) < 1:
            raise SystemExit(f"--agent-seeds: expected LABEL=N with LABEL one of {list(labels)} and N >= 1, "
                             f"got {item!r}")
        counts[label] = int(count)
    return counts


def _run_job(config: TrainConfig, run_dir: Path, tester: Evaluator, seeds: np.ndarray, observations: np.ndarray,
             reference_jerk: np.ndarray) -> dict:
    """One training run (into ``run_dir``; one found there is resumed, e.g. to a longer budget) and the test
    evaluation of its final policy. Every episode goes through an ``Evaluator`` (``train`` builds its own): this is
    the one place where a run is dispatched."""
    began = time.perf_counter()
    run = train(config, run_dir, resume=(run_dir / "config.json").is_file())
    records = run.read_log()
    actions = trained_actions(run, config, "last", observations, tester.n_actions)
    scores = evaluate_actions(tester, actions, seeds, reference_jerk)
    curve = [{key: record.get(key) for key in ("update", "episodes", "eval_success", "eval_coverage",
                                               "eval_return_mean", "return_mean", "exploration")}
             for record in records if record.get("eval_return_mean") is not None]
    return {"agent": config.agent, "seed": config.seed, "seconds": round(time.perf_counter() - began, 1),
            "options": config.options.to_dict(), "episodes_to_target": episodes_to(records, SUCCESS_TARGET),
            "curve": curve,
            "test": scores.to_dict(), "test_means": scores.means(), "code": _code(run)}


def _code(run: RunDirectory) -> dict:
    """The rdmp-gym commit and the package versions that trained ``run`` (``{"commit", "dirty", "packages"}``;
    the cache does not key on them, so a document can hold runs of several commits: :func:`code_versions` lists
    them; the same seed gives the same numbers only with the same numerical packages)."""
    session = run.read_provenance()["sessions"][-1]
    return {**session["rdmp_gym"], "packages": session["packages"]}


def code_versions(runs: list[dict]) -> dict[str, list[str]]:
    """``{commit (+ "-dirty"): ["label-seed", ...]}`` of the runs that record one (older caches do not)."""
    versions: dict[str, list[str]] = {}
    for run in runs:
        code = run.get("code") or {}
        commit = f"{code.get('commit')}{'-dirty' if code.get('dirty') else ''}" if code else "unrecorded"
        versions.setdefault(commit, []).append(f"{run['agent']}-{run['seed']}")
    return versions


def _cache_key(config: TrainConfig, test_seeds: np.ndarray) -> str:
    """Everything a cached run must match to stand for ``config`` tested on ``test_seeds``."""
    fields = {key: value for key, value in vars(config).items() if key != "workers"}
    if not fields["stratified_validation"]:            # runs from before the setting existed keep their key
        del fields["stratified_validation"]
    return json.dumps({**fields, "test_seeds": test_seeds.tolist()}, sort_keys=True, default=str)


def _cached_run(config: TrainConfig, path: Path, test_seeds: np.ndarray) -> dict | None:
    """The run cached at ``path`` if it stands for ``config`` on ``test_seeds``: the same key, or one that differs
    only in how the learner's options were written, e.g. before the learner gained a setting that ``config``
    leaves at its default (its stored options then equal ``config``'s)."""
    if not path.is_file():
        return None
    saved = json.loads(path.read_text())
    wanted = _cache_key(config, test_seeds)
    if saved.get("key") == wanted:
        return saved["run"]
    stored, wanted_fields = json.loads(saved.get("key") or "{}"), json.loads(wanted)
    stored.pop("options", None)
    wanted_fields.pop("options")
    same = stored == wanted_fields and "options" in saved["run"] and _same_options(saved["run"]["options"], config)
    return saved["run"] if same else None


def _store_run(config: TrainConfig, path: Path, test_seeds: np.ndarray, run: dict) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps({"key": _cache_key(config, test_seeds), "run": run}))


def _same_protocol(saved: dict, config: TrainConfig, test_seeds: np.ndarray) -> bool:
    """Whether a results document's ``settings`` trained and tested as ``config`` on ``test_seeds`` does."""
    return (saved["env_id"] == config.env_id and saved["env_kwargs"] == config.env_kwargs
            and saved["budget"] // saved["rollouts"] == config.updates and saved["rollouts"] == config.rollouts
            and saved["val_contexts"] == config.eval_episodes and saved["eval_every"] == config.eval_every
            and saved["final_test_seeds"] == test_seeds.tolist()
            and saved.get("stratified_validation", False) == config.stratified_validation)


def _same_options(saved: dict, config: TrainConfig) -> bool:
    """Whether a stored run's options (also as earlier versions stored them: the given ones, comma strings) are
    the settings of ``config``."""
    try:
        return type(config.options).from_dict(saved, config.agent) == config.options
    except (TypeError, ValueError):
        return False


def reusable_runs(documents: list[dict], configs: list[TrainConfig], names: list[str],
                  test_seeds: np.ndarray) -> dict[tuple[str, int], dict]:
    """``{(label, seed): run}`` from earlier results documents for the configs they match in every setting
    (learner, budget, rollouts, validation protocol, env, test contexts and the learner's options)."""
    found: dict[tuple[str, int], dict] = {}
    for document in documents:
        learners = _labels(document["settings"]["agents"])
        runs = {(run["agent"], run["seed"]): run for run in document["runs"]}
        for name, config in zip(names, configs, strict=True):
            run = runs.get((name, config.seed))
            if (run is not None and learners.get(name) == config.agent and _same_options(run["options"], config)
                    and _same_protocol(document["settings"], config, test_seeds)):
                found.setdefault((name, config.seed), run)
    return found


def _run_remote(config: TrainConfig, run_dir: Path, spec: TaskSpec, seeds: np.ndarray, observations: np.ndarray,
                reference_jerk: np.ndarray) -> dict:
    """:func:`_run_job` inside a Ray task: its own one-worker test evaluator."""
    with Evaluator(spec, 1) as tester:
        return _run_job(config, run_dir, tester, seeds, observations, reference_jerk)


def _run_on_ray(configs: list[TrainConfig], names: list[str], args: argparse.Namespace, scratch: Path, spec: TaskSpec,
                seeds: np.ndarray, observations: np.ndarray, reference_jerk: np.ndarray) -> list[dict]:
    """Every run as a Ray task (one CPU, one worker inside); results in the order of ``configs``."""
    from rdmp_gym.agents.ray_backend import import_ray, init_ray

    ray = import_ray()
    owns = init_ray(args.workers, args.ray_address)
    remote = ray.remote(num_cpus=1)(_run_remote)
    try:
        pending = [remote.remote(config, scratch / f"{name}-{config.seed}", spec, seeds, observations, reference_jerk)
                   for name, config in zip(names, configs, strict=True)]
        with tqdm(total=len(pending), desc="runs (ray)", unit="run") as bar:
            for ref in pending:
                ray.wait([ref], num_returns=1)
                bar.update(1)
        return ray.get(pending)
    finally:
        if owns:
            ray.shutdown()


def _run_locally(configs: list[TrainConfig], names: list[str], args: argparse.Namespace, scratch: Path, spec: TaskSpec,
                 seeds: np.ndarray, observations: np.ndarray, reference_jerk: np.ndarray) -> list[dict]:
    """The runs one after the other; each finished run is cached, so an interrupted call resumes where it stopped."""
    cache = SCRATCH / f"{args.name}-runs"
    earlier = reusable_runs([json.loads(Path(path).read_text()) for path in args.reuse], configs, names, seeds)
    if args.reuse:
        print(f"{len(earlier)} run(s) taken from {', '.join(args.reuse)}")
    runs = []
    with Evaluator(spec, args.workers) as tester:
        for name, config in tqdm(list(zip(names, configs, strict=True)), desc="runs", unit="run"):
            path = cache / f"{name}-{config.seed}.json"
            run = (None if args.fresh else _cached_run(config, path, seeds)) or earlier.get((name, config.seed))
            if run is None:
                run = _run_job(config, scratch / f"{name}-{config.seed}", tester, seeds, observations,
                               reference_jerk)
                _store_run(config, path, seeds, run)
            runs.append(run)
    return runs


def _baselines(spec: TaskSpec, seeds: np.ndarray, workers: int) -> tuple[dict[str, dict], np.ndarray, np.ndarray]:
    """The no-learning rows' per-context scores (``imitation``, ``coupling``), the test observations and the
    imitation's path jerk per context."""
    from obstacle_baseline import coupling_baseline_scores

    with Evaluator(spec, workers) as tester:
        observations = context_observations(tester.env, seeds)
        n = tester.n_actions
        reference = np.array([path_jerk(tester.env, np.zeros(n), s) for s in seeds])
        imitation = evaluate_actions(tester, np.zeros((len(seeds), n)), seeds, reference).to_dict()
        if not hasattr(getattr(tester.env.unwrapped, "task", None), "hand_cup_gaps"):   # coupling lifts over the cup
            return {"imitation": imitation}, observations, reference
        coupling = coupling_baseline_scores(tester.env, seeds)
    coupling = {key: np.asarray(value).tolist() for key, value in coupling.items() if key in imitation}
    return {"imitation": imitation, "coupling": coupling}, observations, reference


def _interval(values: list | np.ndarray, statistic: str) -> dict | None:
    """The interval of ``values``, or None where the task has no such figure (e.g. coverage on a drum: NaN)."""
    values = np.asarray(values, dtype=float)
    return None if np.isnan(values).all() else interval(values, statistic).to_dict()


def _scores(scores: dict, metric: str) -> list:
    """The per-context values of ``metric`` (NaN where the task has no such figure: e.g. no coverage on a drum, no
    success reported)."""
    values = scores.get(metric)
    return [np.nan] * len(scores["returns"]) if values is None else values


def _summary(runs: list[dict], baselines: dict[str, dict]) -> list[dict]:
    rows = [{"agent": name, "n": len(scores["returns"]), "over": "contexts",
             **{m: _interval(_scores(scores, m), "mean") for m in METRICS},
             "reached": None, "episodes_to_target": None} for name, scores in baselines.items()]
    for agent in dict.fromkeys(r["agent"] for r in runs):
        group = [r for r in runs if r["agent"] == agent]
        reached = [r["episodes_to_target"] for r in group if r["episodes_to_target"] is not None]
        rows.append({"agent": agent, "n": len(group), "over": "seeds",
                     **{m: _interval([r["test_means"].get(m, np.nan) for r in group], "iqm") for m in METRICS},
                     "reached": len(reached), "episodes_to_target": float(np.median(reached)) if reached else None})
    return rows


def _cell(entry: dict | None, digits: int = 3) -> str:
    if entry is None:
        return "-"
    return f"{entry['estimate']:.{digits}f} [{entry['low']:.{digits}f}, {entry['high']:.{digits}f}]"


def _print(rows: list[dict], settings: dict) -> None:
    header = (f"{'agent':>10} {'n':>9} {'success rate':>22} {'coverage':>22} {'jerk / imitation':>22} "
              f"{'return':>22} {'val. success >= 0.9 (median ep.)':>32}")
    print(header)
    for r in rows:
        median = "-" if r["episodes_to_target"] is None else str(int(r["episodes_to_target"]))
        target = "-" if r["reached"] is None else f"{r['reached']}/{r['n']} seeds ({median})"
        count = f"{r['n']} {r['over']}"
        print(f"{r['agent']:>10} {count:>9} {_cell(r['success']):>22} {_cell(r['coverage']):>22} "
              f"{_cell(r['jerk_ratio']):>22} {_cell(r['returns']):>22} {target:>32}")
    print(f"(final policies on {settings['test_contexts']} test contexts; IQM over seeds with 95 % bootstrap CI; "
          f"no-learning rows: mean over contexts with CI; budget {settings['budget']} episodes; "
          f"env {settings['env_id']})")


def markdown_table(rows: list[dict], field: dict) -> str:
    """The summary ``rows`` as a Markdown table, with each learner's episodes to the validation success levels of
    the field report ``field`` (median over the seeds that reach it, and how many do)."""
    lines = ["| policy | test success rate | test coverage | jerk / imitation | test return | "
             "val. success 0.5 / 0.8 / 0.9 (median episodes, seeds) |", "|---|---|---|---|---|---|"]
    for r in rows:
        levels = field["agents"].get(r["agent"], {}).get("episodes_to", {})
        reached = " / ".join(f"{'-' if e['median'] is None else int(e['median'])} ({e['reached']}/{r['n']})"
                             for e in levels.values())
        cells = [_cell(r[metric], digits) for metric, digits in
                 (("success", 2), ("coverage", 3), ("jerk_ratio", 2), ("returns", 3))]
        lines.append(f"| `{r['agent']}` ({r['n']} {r['over']}) | {' | '.join(cells)} | {reached} |")
    return "\n".join(lines)


def _report(document: dict, folder: Path, name: str, markdown: bool = False) -> None:
    """Print the table, draw ``<name>.png`` and write the field report (``<name>_field.json/.png``) in ``folder``."""
    title = _title(document["settings"])
    _print(document["summary"], document["settings"])
    _plot(document["runs"], document["summary"], folder / f"{name}.png", title)
    field = write_field_report(document, folder, name, title)
    if markdown:
        print(markdown_table(document["summary"], field))
    for agent, entry in field["agents"].items():
        counts = entry["failure_causes"]
        if counts["runs"]:
            causes = ", ".join(f"{cause} {n}" for cause, n in counts["causes"].items()) or "none"
            print(f"{agent}: {counts['failures']} failed (seed, test context) pairs in {counts['runs']} run(s) that "
                  f"name their causes: {causes}")
        for kind, row in (entry["by_kind"] or {}).items():
            named = ", ".join(f"{cause} {n}" for cause, n in row["causes"].items()) or "none"
            print(f"    {kind} ({row['contexts']} contexts): success {row['success']:.2f}, "
                  f"{row['failures']} failed pairs: {named}")
    hardest = ", ".join(f"{h['index']} ({h['success']:.2f})" for h in field["hardest"]) or "none"
    print(f"test contexts that {field['best']} solves in fewer than half of its seeds (index, share): {hardest}")


def _plot(runs: list[dict], rows: list[dict], path: Path, title: str) -> None:
    figure, axes = plt.subplots(1, 4, figsize=(18, 4))
    agents = list(dict.fromkeys(r["agent"] for r in runs))
    imitation = next(r for r in rows if r["agent"] == "imitation")
    curves = ((0, "eval_success", "validation success rate"), (1, "eval_coverage", "validation coverage"))
    covered = any(c.get("eval_coverage") is not None and np.isfinite(c["eval_coverage"]) for r in runs
                  for c in r["curve"])
    for col, key, label in curves[:None if covered else 1]:
        axis = axes[col]
        for index, agent in enumerate(agents):
            group = [r for r in runs if r["agent"] == agent]
            length = min(len(r["curve"]) for r in group)
            episodes = np.array([c["episodes"] for c in group[0]["curve"][:length]])
            values = np.array([[np.nan if c[key] is None else c[key] for c in r["curve"][:length]] for r in group])
            axis.plot(episodes, np.nanmedian(values, axis=0), color=f"C{index}", label=agent)
            axis.fill_between(episodes, np.nanpercentile(values, 25, axis=0), np.nanpercentile(values, 75, axis=0),
                              color=f"C{index}", alpha=0.15)
        axis.set_title(f"{label} (median, IQR over seeds)", fontsize=9)
        axis.set_xlabel("training episodes")
        axis.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    if not covered:
        axes[1].set_axis_off()
        axes[1].set_title("validation coverage: the task has none", fontsize=9)
    for col, metric, label in ((2, "success", "test success rate"), (3, "jerk_ratio", "test jerk / imitation")):
        axis = axes[col]
        shown = [imitation] + [r for r in rows if r["agent"] != "imitation"]
        colours = ["0.6" if r["agent"] not in agents else f"C{agents.index(r['agent'])}" for r in shown]
        estimates = [r[metric]["estimate"] for r in shown]
        errors = np.array([[r[metric]["estimate"] - r[metric]["low"], r[metric]["high"] - r[metric]["estimate"]]
                           for r in shown]).T
        axis.bar(range(len(shown)), estimates, yerr=errors, capsize=3,
                 color=colours)
        axis.set_xticks(range(len(shown)), [r["agent"] for r in shown], rotation=45, fontsize=8)
        axis.set_title(f"{label} (IQM, 95 % CI)", fontsize=9)
        axis.grid(alpha=0.3, axis="y")
    axes[3].axhline(2.0, color="k", ls=":", lw=0.8)
    figure.suptitle(title)
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def run_settings(args: argparse.Namespace, env_kwargs: dict, options: dict, seeds: np.ndarray) -> dict:
    """The ``settings`` of the results document: the command line (less what only steers this call) and what it
    resolved to."""
    settings = {key: value for key, value in vars(args).items()
                if key not in ("option", "env_option", "replot", "ray_address")}
    settings.update({"env_kwargs": env_kwargs, "options": options, "cpus": os.cpu_count(),
                     "final_test_seeds": seeds.tolist(), "success_target": SUCCESS_TARGET})
    return settings


def _title(settings: dict) -> str:
    fewer = "".join(f", {item.replace('=', ' ')}" for item in settings.get("agent_seeds", []))
    return (f"{settings['env_id']}: {settings['budget']} episodes, {settings['seeds']} seed(s){fewer}, "
            f"{settings['test_contexts']} test contexts")


def main() -> None:
    import torch

    torch.set_num_threads(1)
    args = _parse()
    RESULTS = results_dir(args.save)
    if args.replot or args.update_baselines:
        path = RESULTS / f"{args.name}.json"
        document = json.loads(path.read_text())
        if args.update_baselines:
            saved = document["settings"]
            spec = TaskSpec(saved["env_id"], saved["env_kwargs"])
            baselines, observations, _ = _baselines(spec, np.asarray(saved["final_test_seeds"]), args.workers)
            document["baselines"], document["test_contexts"] = baselines, observations.tolist()
            document.pop("imitation", None)
            document["summary"] = _summary(document["runs"], document["baselines"])
            path.write_text(json.dumps(document, indent=1) + "\n")
        _report(document, RESULTS, args.name, args.markdown)
        return
    env_kwargs = {key: _value(value) for key, value in (item.partition("=")[::2] for item in args.env_option)}
    options = _options(args)
    spec = TaskSpec(args.env_id, env_kwargs)
    seeds = final_test_seeds(args.test_contexts)
    scratch = Path(args.run_dir) if args.run_dir else Path(tempfile.mkdtemp(prefix="bench_agents_"))
    runs = []
    try:
        baselines, observations, reference = _baselines(spec, seeds, 1 if args.backend == "ray" else args.workers)
        workers = 1 if args.backend == "ray" else args.workers
        labels = _labels(args.agents)
        counts = _seed_counts(args, labels)
        configs = [TrainConfig(agent=learner, env_id=args.env_id, updates=args.budget // args.rollouts,
                               rollouts=args.rollouts, seed=seed, workers=workers, env_kwargs=env_kwargs,
                               options=options.get(label, {}), eval_episodes=args.val_contexts,
                               eval_every=args.eval_every, shared_context=False,
                               stratified_validation=args.stratified_validation)
                   for label, learner in labels.items() for seed in range(counts[label])]
        names = [label for label in labels for _ in range(counts[label])]
        if args.only_seeds is not None:
            first, stop = args.only_seeds
            chosen = [i for i, config in enumerate(configs) if first <= config.seed < stop]
            configs, names = [configs[i] for i in chosen], [names[i] for i in chosen]
        if args.backend == "ray":
            runs = _run_on_ray(configs, names, args, scratch, spec, seeds, observations, reference)
        else:
            runs = _run_locally(configs, names, args, scratch, spec, seeds, observations, reference)
        runs = [{**run, "agent": name} for name, run in zip(names, runs, strict=True)]
    finally:
        if not args.run_dir:
            shutil.rmtree(scratch, ignore_errors=True)
    if args.only_seeds is not None:
        print(f"cached {len(runs)} run(s) of seeds {args.only_seeds[0]}..{args.only_seeds[1] - 1}")
        return
    rows = _summary(runs, baselines)
    settings = run_settings(args, env_kwargs, options, seeds)
    document = {"settings": settings, "summary": rows, "baselines": baselines, "runs": runs,
                "test_contexts": np.asarray(observations).tolist()}
    (RESULTS / f"{args.name}.json").write_text(json.dumps(document, indent=1) + "\n")
    _report(document, RESULTS, args.name, args.markdown)
    for commit, names in code_versions(runs).items():
        print(f"code {commit}: {len(names)} run(s)")
    print(f"wrote {RESULTS / (args.name + '.json')}, {args.name}.png and {args.name}_field.json/.png")


if __name__ == "__main__":
    main()
