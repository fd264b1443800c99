"""The learners' results as the field reports them (Agarwal et al., NeurIPS 2021), from a ``bench_agents`` document.

- sample-efficiency curves: the IQM over seeds of the validation success rate against training episodes, with
  95 % stratified-bootstrap bands, the imitation's test rate and the task's ceiling (the per-context search of
  ``bench_solvable``) drawn on the same axes;
- final scores: the IQM over seeds of the test success rate with its interval;
- performance profiles: the fraction of (seed, test context) pairs whose coverage exceeds each threshold;
- the probability that a run of one learner succeeds on a test context where a run of another does not
  (``P(X > Y)`` on per-context success, ties one half), for every pair (the figure: the best learner's);
- episodes until the validation success rate first reaches 0.5, 0.8 and 0.9 (median over the seeds that do);
- why the final policies fail: per learner, how many (seed, test context) pairs miss each success criterion
  (the env's ``failure_causes``: coverage, force, cup, collisions, joint acceleration or limit), from the runs
  that recorded them;
- by kind of test context (where the env names kinds, ``context_kind``; wiping: cup on the approach, cup beside the
  patch, largest patch, no cup): per learner, how many test contexts of each kind, the share of (seed, context)
  pairs that succeed and the criteria the failed ones miss;
- each learner's hardest test contexts (the figure and the top-level ``hardest``: the best learner's): those it
  solves in fewer than half of its seeds, with their context vectors (where the document holds them), to read
  what they share.

Writes ``<name>_field.json`` and ``<name>_field.png`` beside the document:

    python benchmarks/field_report.py benchmarks/results/agents_v2.json
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from rdmp_gym.agents.field_metrics import (
    curve_intervals,
    performance_profile,
    probability_of_improvement,
    stratified_interval,
)
from rdmp_gym.agents.tasks import failure_contexts

TARGETS = (0.5, 0.8, 0.9)
THRESHOLDS = np.linspace(0.8, 1.0, 41)
SOLVABLE = Path(__file__).resolve().parent / "results" / "solvable_v2.json"


def _agents(runs: list[dict]) -> list[str]:
    return list(dict.fromkeys(r["agent"] for r in runs))


def _curves(group: list[dict]) -> tuple[np.ndarray, np.ndarray]:
    """``([P], [R, P])`` episodes and validation success of the runs of one agent (their common length)."""
    length = min(len(r["curve"]) for r in group)
    episodes = np.array([c["episodes"] for c in group[0]["curve"][:length]], dtype=float)
    values = np.array([[c["eval_success"] for c in r["curve"][:length]] for r in group], dtype=float)
    return episodes, values


def episodes_to(curve: list[dict], target: float) -> int | None:
    """Training episodes until the validation success rate first reaches ``target`` (None: never)."""
    for record in curve:
        if record.get("eval_success") is not None and record["eval_success"] >= target:
            return int(record["episodes"])
    return None


def ceiling(test_seeds: list[int], env_id: str) -> dict | None:
    """The share of the test contexts that the per-context search solved (``solvable_v2.json``), if it covers them."""
    if not SOLVABLE.is_file():
        return None
    document = json.loads(SOLVABLE.read_text())
    if document["settings"].get("env_id") != env_id:
        return None
    solved = {row["seed"]: row["solved"] for row in document["contexts"]}
    if not all(seed in solved for seed in test_seeds):
        return None
    flags = np.array([solved[seed] for seed in test_seeds], dtype=float)
    return {"success": float(flags.mean()), "contexts": len(flags)}


def hardest_contexts(success: np.ndarray, test_seeds: list[int], contexts: list | None) -> list[dict]:
    """The test contexts that fewer than half of the runs solve, ``success [R, M]``, hardest first: index, seed,
    share of runs that succeed, and the context vector (``contexts [M, C]``, or None)."""
    rates = success.mean(axis=0)
    order = [int(i) for i in np.argsort(rates, kind="stable") if rates[i] < 0.5]
    return [{"index": i, "seed": int(test_seeds[i]), "success": float(rates[i]),
             "context": None if contexts is None else [round(float(v), 4) for v in contexts[i]]} for i in order]


def failure_counts(runs: list[dict]) -> dict:
    """``{"runs": R, "failures": F, "causes": {cause: pairs}}`` over the runs whose test results name the missed
    criteria (a pair may miss several, so the causes can sum to more than ``F``), most frequent first."""
    named = [r["test"]["failures"] for r in runs if r["test"].get("failures") is not None]
    causes: dict[str, int] = {}
    for failures in named:
        for cause, found in failure_contexts(failures).items():
            causes[cause] = causes.get(cause, 0) + len(found)
    return {"runs": len(named), "failures": sum(bool(entry) for failures in named for entry in failures),
            "causes": dict(sorted(causes.items(), key=lambda item: -item[1]))}


def context_kinds(document: dict) -> list[str] | None:
    """The kind of each test context of ``document`` (the ``context_kind`` of its env's task contract, of the stored
    test contexts), or None where the task names no kinds or the document holds no contexts."""
    contexts = document.get("test_contexts")
    if not contexts:
        return None
    import gymnasium as gym
    import rdmp_gym.envs  # noqa: F401  (registers the ids)
    from rdmp_gym.envs.contract import contract_of

    settings = document["settings"]
    env = gym.make(settings["env_id"], disable_env_checker=True, **settings.get("env_kwargs", {}))
    kind_of = contract_of(env).context_kind
    kinds = None if kind_of is None else [str(kind_of(np.asarray(c, dtype=float))) for c in contexts]
    env.close()
    return kinds


def by_kind(runs: list[dict], kinds: list[str]) -> dict:
    """``{kind: {"contexts", "success", "failures", "causes"}}`` over the (seed, test context) pairs of ``runs``
    (one agent's), by the kind of the test context; causes only from runs that name them."""
    result: dict[str, dict] = {}
    for kind in dict.fromkeys(kinds):
        where = [i for i, k in enumerate(kinds) if k == kind]
        success = np.array([[r["test"]["success"][i] for i in where] for r in runs], dtype=float)
        causes: dict[str, int] = {}
        for run in runs:
            failures = run["test"].get("failures")
            for i in where if failures is not None else ():
                for cause in filter(None, failures[i].split("+")):
                    causes[cause] = causes.get(cause, 0) + 1
        result[kind] = {"contexts": len(where), "success": float(success.mean()),
                        "failures": int((success == 0).sum()),
                        "causes": dict(sorted(causes.items(), key=lambda item: -item[1]))}
    return result


def field_summary(document: dict) -> dict:
    """Every number of the module docstring, per agent; ``best`` is the agent with the highest IQM test success."""
    runs, agents = document["runs"], _agents(document["runs"])
    kinds = context_kinds(document)
    result: dict = {"context_kinds": kinds, "agents": {}, "thresholds": THRESHOLDS.tolist(),
                    "ceiling": ceiling(document["settings"]["final_test_seeds"], document["settings"]["env_id"]),
                    "imitation_success": float(np.mean(document["baselines"]["imitation"]["success"]))}
    success = {agent: np.array([r["test"]["success"] for r in runs if r["agent"] == agent], dtype=float)
               for agent in agents}
    for agent in agents:
        group = [r for r in runs if r["agent"] == agent]
        episodes, values = _curves(group)
        coverage = np.array([r["test"].get("coverage") or [np.nan] * len(r["test"]["returns"]) for r in group],
                            dtype=float)
        covered = not np.isnan(coverage).all()          # a task without dirt (drumming) has no coverage
        reached = {str(t): [episodes_to(r["curve"], t) for r in group] for t in TARGETS}
        result["agents"][agent] = {
            "seeds": len(group),
            "test_success": stratified_interval(success[agent].mean(axis=1, keepdims=True)).to_dict(),
            "test_coverage": stratified_interval(coverage).to_dict() if covered else None,
            "curve_episodes": episodes.tolist(), "curve": curve_intervals(values).tolist(),
            "coverage_profile": performance_profile(coverage, THRESHOLDS).tolist() if covered else None,
            "failure_causes": failure_counts(group),
            "by_kind": None if kinds is None else by_kind(group, kinds),
            "episodes_to": {t: {"reached": sum(e is not None for e in v),
                                "median": float(np.median([e for e in v if e is not None])) if any(
                                    e is not None for e in v) else None} for t, v in reached.items()},
            "hardest": hardest_contexts(success[agent], document["settings"]["final_test_seeds"],
                                        document.get("test_contexts")),
            "improvement": {other: probability_of_improvement(success[agent], success[other]).to_dict()
                            for other in agents if other != agent}}
    best = max(agents, key=lambda a: result["agents"][a]["test_success"]["estimate"])
    result["best"] = best
    result["hardest"] = result["agents"][best]["hardest"]
    result["improvement"] = result["agents"][best]["improvement"]
    return result


def plot(summary: dict, path: Path, title: str) -> None:
    """The four panels: curves, final scores, coverage profiles, probability of improvement."""
    agents = list(summary["agents"])
    figure, axes = plt.subplots(1, 4, figsize=(20, 4.2))
    for index, agent in enumerate(agents):
        entry = summary["agents"][agent]
        episodes, band = np.array(entry["curve_episodes"]), np.array(entry["curve"])
        axes[0].plot(episodes, band[:, 0], color=f"C{index}", label=agent)
        axes[0].fill_between(episodes, band[:, 1], band[:, 2], color=f"C{index}", alpha=0.15)
        if entry["coverage_profile"] is None:
            continue
        profile = np.array(entry["coverage_profile"])
        axes[2].plot(summary["thresholds"], profile[:, 0], color=f"C{index}", label=agent)
        axes[2].fill_between(summary["thresholds"], profile[:, 1], profile[:, 2], color=f"C{index}", alpha=0.15)
    for axis in axes[:2]:
        axis.axhline(summary["imitation_success"], color="0.5", ls="--", lw=1, label="imitation (test)")
        if summary["ceiling"] is not None:
            axis.axhline(summary["ceiling"]["success"], color="k", ls=":", lw=1, label="per-context search (ceiling)")
    axes[0].set(title="validation success (IQM, 95 % stratified bootstrap)", xlabel="training episodes")
    axes[0].legend(fontsize=7)
    finals = [summary["agents"][a]["test_success"] for a in agents]
    axes[1].bar(range(len(agents)), [f["estimate"] for f in finals], color=[f"C{i}" for i in range(len(agents))],
                yerr=np.array([[f["estimate"] - f["low"], f["high"] - f["estimate"]] for f in finals]).T, capsize=3)
    axes[1].set_xticks(range(len(agents)), agents, rotation=45, fontsize=8)
    axes[1].set(title="test success of the final policy (IQM, 95 % CI)", ylim=(0, 1.05))
    axes[2].set(title="coverage profile: P(coverage > t) over seeds x contexts", xlabel="t")
    others = list(summary["improvement"])
    entries = [summary["improvement"][o] for o in others]
    axes[3].barh(range(len(others)), [e["estimate"] for e in entries], color="C0",
                 xerr=np.array([[e["estimate"] - e["low"], e["high"] - e["estimate"]] for e in entries]).T, capsize=3)
    axes[3].set_yticks(range(len(others)), others, fontsize=8)
    axes[3].axvline(0.5, color="k", lw=0.8)
    axes[3].set(title=f"P({summary['best']} > Y) on test success", xlim=(0, 1))
    for axis in axes:
        axis.grid(alpha=0.3)
    figure.suptitle(title)
    figure.tight_layout()
    figure.savefig(path, dpi=100)
    plt.close(figure)


def write(document: dict, folder: Path, name: str, title: str) -> dict:
    """Compute, save ``<name>_field.json`` and ``.png`` in ``folder``, return the summary."""
    summary = field_summary(document)
    (folder / f"{name}_field.json").write_text(json.dumps(summary, indent=1) + "\n")
    plot(summary, folder / f"{name}_field.png", title)
    return summary


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("document", type=Path, help="a bench_agents result (JSON)")
    args = parser.parse_args()
    document = json.loads(args.document.read_text())
    settings = document["settings"]
    summary = write(document, args.document.parent, args.document.stem,
                    f"{settings['env_id']}: {settings['seeds']} seeds, {settings['test_contexts']} test contexts")
    for agent, entry in summary["agents"].items():
        reached = ", ".join(f"{t}: {v['median'] or '-'} ({v['reached']}/{entry['seeds']})"
                            for t, v in entry["episodes_to"].items())
        success = entry["test_success"]
        print(f"{agent:>10}  test success {success['estimate']:.3f} [{success['low']:.3f}, {success['high']:.3f}]"
              f"  episodes to validation success {reached}")


if __name__ == "__main__":
    main()
