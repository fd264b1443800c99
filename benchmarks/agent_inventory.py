"""Which agents and options the committed results use: for every registered agent and every option field, the
committed results (``benchmarks/results/*.json``) that ran it, on which env ids, with which values, and whether a
benchmark script sets it.

Sources read: the ``bench_agents`` documents (``settings.agents`` as ``label=learner``, each run's ``options``, the
effective settings; older documents hold only the given ones, read over the task's learner defaults), the
locomotion documents (``settings.learners``), the validation-curve documents (``rows.*.command``, bench_agents
command lines), the credit toy (``bench_credit_toy.CONDITIONS``), and the documents that name agents without
options (``bench_second_task``, ``bench_step``, ``bench_step_twin``: the agents' defaults). An option's use is
``set`` where a run gave it a value other than its default, ``default`` where runs ran it at its default only, and
``absent`` where no committed run of its agent ran at all. A result is ``cited`` when README.md or a page of docs/
names its file.

    python benchmarks/agent_inventory.py          # the table, and the counts
    python benchmarks/agent_inventory.py --save   # also benchmarks/results/agent_inventory.json
"""

from __future__ import annotations

import argparse
import dataclasses
import fnmatch
import itertools
import json
import re
import shlex
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from output import COMMITTED, add_save_argument, results_dir
from rdmp_gym.agents import learners, sb3_config  # noqa: F401  (each declares its agents)
from rdmp_gym.agents.registry import REGISTRY
from rdmp_gym.agents.tasks import task_options

ROOT = Path(__file__).resolve().parent.parent
#: the tasks the agents are measured on now; a wiping result on an earlier version (v1, v2) is an old one
CURRENT = ("rdmp_gym/ArmarWipe-v3", "rdmp_gym/PandaWipe-v3", "rdmp_gym/ArmarDrum-v1", "rdmp_gym/PandaDrum-v1",
           "Swimmer-v5", "HalfCheetah-v5")
OLD = re.compile(r"Wipe(Step)?-v[12]$")
#: documents that name agents but no options: (agents, env id) per file stem
_NO_OPTIONS = {"step": (("pi2",), "rdmp_gym/ArmarWipe-v1"), "second_task": (None, None)}


@dataclasses.dataclass
class Use:
    """One committed run's agent and its options (``label`` its name in the document)."""

    source: str
    env_id: str
    label: str
    agent: str
    options: dict[str, Any]
    given_only: bool = False     # only the given options are known: read them over the task's learner defaults


def _labels(agents: list[str]) -> dict[str, str]:
    """``{label: learner}`` of a bench_agents ``settings.agents`` list (``label=learner`` or ``learner``)."""
    return dict((item.partition("=")[0], item.partition("=")[2] or item) for item in agents)


def _bench_agents_uses(name: str, document: dict) -> Iterator[Use]:
    settings = document["settings"]
    labels = _labels(settings["agents"])
    runs = document.get("runs") or []
    for run in runs:
        if "options" in run and run["agent"] in labels:
            yield Use(name, settings["env_id"], run["agent"], labels[run["agent"]], dict(run["options"]),
                      given_only=len(run["options"]) < len(dataclasses.fields(REGISTRY[labels[run["agent"]]].config))
                      if labels[run["agent"]] in REGISTRY else True)
    if not any("options" in run for run in runs):            # documents whose runs do not record options
        for label, agent in labels.items():
            yield Use(name, settings["env_id"], label, agent, dict((settings.get("options") or {}).get(label, {})),
                      given_only=True)


def _command_uses(name: str, document: dict) -> Iterator[Use]:
    """The rows of a validation-curve document, each a bench_agents command line."""
    env = re.search(r"--env-id (\S+)", document.get("about", ""))
    for row in document["rows"].values():
        words = shlex.split(row["command"])
        agents = words[words.index("--agents") + 1:]
        agents = agents[:next((i for i, w in enumerate(agents) if w.startswith("--")), len(agents))]
        options: dict[str, dict[str, Any]] = {}
        for flag, value in itertools.pairwise(words):
            if flag == "--option":
                key, _, text = value.partition("=")
                label, _, option = key.partition(".")
                options.setdefault(label, {})[option] = _value(text)
        for label, agent in _labels(agents).items():
            yield Use(name, env.group(1) if env else "?", label, agent, options.get(label, {}), given_only=True)


def _value(text: str) -> Any:
    """A ``--option`` value as bench_agents reads it (JSON where it parses, else the string)."""
    try:
        return json.loads(text)
    except json.JSONDecodeError:
        return text


def _credit_toy_uses(name: str, document: dict) -> Iterator[Use]:
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from bench_credit_toy import CONDITIONS

    rough = document["settings"].get("rough")
    for condition in dict.fromkeys(run["condition"] for run in document["runs"]):
        options = dict(CONDITIONS[condition][0])
        if rough is not None:
            options["rough"] = rough
        yield Use(name, "credit toy (bench_credit_toy.py)", condition, "bbrl", options)


def _locomotion_uses(name: str, document: dict) -> Iterator[Use]:
    settings = document["settings"]
    ran = {(run["env"], run["learner"]) for run in document["runs"]}
    for env_id, label in sorted(ran):
        entry = settings["learners"].get(label, {"agent": label, "options": {}})
        yield Use(name, env_id, label, entry["agent"], dict(entry["options"]), given_only=True)


def uses() -> list[Use]:
    """Every committed run's agent and options."""
    found: list[Use] = []
    for path in sorted(COMMITTED.glob("*.json")):
        if path.stem == "agent_inventory":
            continue
        document = json.loads(path.read_text())
        if not isinstance(document, dict):
            continue
        settings = document.get("settings") or {}
        if path.stem.startswith("credit_toy"):
            found += _credit_toy_uses(path.name, document)
        elif "learners" in settings and "envs" in settings:
            found += _locomotion_uses(path.name, document)
        elif isinstance(document.get("rows"), dict) and all("command" in r for r in document["rows"].values()):
            found += _command_uses(path.name, document)
        elif path.stem in _NO_OPTIONS:
            agents, env_id = _NO_OPTIONS[path.stem]
            for agent in agents or settings["agents"]:
                found.append(Use(path.name, env_id or settings["env_id"], agent, agent, {}, given_only=True))
        elif "agents" in settings and "env_id" in settings and "options" not in settings:   # bench_step_twin
            found += [Use(path.name, settings["env_id"], agent, agent, {}, given_only=True)
                      for agent in settings["agents"]]
        elif "agents" in settings and "env_id" in settings:
            found += _bench_agents_uses(path.name, document)
    return found


def _effective(use: Use) -> tuple[dict[str, Any], list[str]]:
    """``(fields, unknown)``: every option field of the run's agent as the run had it (its default where the run did
    not give it), and the names it gave that the agent no longer has."""
    spec = REGISTRY[use.agent]
    options = use.options
    if use.given_only and use.env_id.startswith("rdmp_gym/"):
        options = task_options(use.env_id, use.agent, options)
    names = {field.name for field in dataclasses.fields(spec.config)}
    unknown = sorted(set(options) - names)
    config = spec.config.from_dict({k: v for k, v in options.items() if k in names}, use.agent)
    return config.to_dict(), unknown


def cited_results() -> set[str]:
    """The result files that README.md or a page of docs/ names (``name.json``, also as a glob)."""
    text = "\n".join(path.read_text() for path in [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))])
    patterns = set(re.findall(r"[\w*.\-]+\.json", text))
    names = [path.name for path in COMMITTED.glob("*.json")]
    return {name for name in names if any(fnmatch.fnmatch(name, pattern.split("/")[-1]) for pattern in patterns)}


def script_settings() -> dict[str, list[str]]:
    """``{option: [script, ...]}``: the benchmark scripts that set an option, by a textual scan of
    ``benchmarks/*.py``: ``--option LABEL.name=``, or ``"name":`` on a line that gives a learner its options (it
    names ``options``, or a dict follows an agent's name or opens a tuple, as in ``("cpi2", {"gain_prior": 10})``)."""
    found: dict[str, list[str]] = {}
    names = {field.name for spec in REGISTRY.values() for field in dataclasses.fields(spec.config)}
    for path in sorted(Path(__file__).resolve().parent.glob("*.py")):
        if path.name == Path(__file__).name:
            continue
        lines = path.read_text().splitlines()
        for name in names:
            if any(re.search(rf"--option\S*[ =]\S*\.{name}=", line)
                   or (re.search(rf"[\"']{name}[\"']\s*:", line) and re.search(r"options|:\s*\(\{|[\"'], \{", line))
                   for line in lines):
                found.setdefault(name, []).append(path.name)
    return found


def _kind(env_id: str) -> str:
    """``current`` (a task the agents are measured on now), ``old`` (an earlier wiping version) or ``other``."""
    return "current" if env_id in CURRENT else "old" if OLD.search(env_id) else "other"


def _add(items: list, value: Any) -> None:
    if value not in items:
        items.append(value)


def inventory() -> dict[str, Any]:
    """Per agent and option: the runs, env ids and values of the committed results, and the scripts that set it."""
    cited, scripts = cited_results(), script_settings()
    table: dict[str, Any] = {}
    all_uses = [use for use in uses() if use.agent in REGISTRY]
    for name, spec in REGISTRY.items():
        defaults = spec.config().to_dict()
        mine = [use for use in all_uses if use.agent == name]
        options: dict[str, Any] = {}
        for field in defaults:
            options[field] = {"default": defaults[field], "use": "absent" if not mine else "default",
                              "set": {}, "scripts": scripts.get(field, [])}
        retired: dict[str, Any] = {}
        for use in mine:
            values, unknown = _effective(use)
            for field, value in values.items():
                if value != defaults[field]:
                    entry = options[field]
                    entry["use"] = "set"
                    where = entry["set"].setdefault(use.source, {"env_ids": [], "cited": use.source in cited,
                                                                 "values": []})
                    _add(where["env_ids"], use.env_id)
                    _add(where["values"], value)
            for field in unknown:
                retired.setdefault(field, {}).setdefault(use.source, []).append(use.options[field])
        runs: dict[str, Any] = {}
        for use in mine:
            _add(runs.setdefault(use.source, {"env_ids": [], "cited": use.source in cited})["env_ids"], use.env_id)
        for entry in runs.values():
            entry["kinds"] = sorted({_kind(env_id) for env_id in entry["env_ids"]})
        table[name] = {"kind": spec.kind, "runs": runs, "options": options, "fixed": spec.config.fixed_values(),
                       "unknown_in_results": retired}
    return table


def counts(table: dict[str, Any]) -> dict[str, Any]:
    """Agents, option fields and distinct option names: registered, and those some committed run used."""
    fields = [(agent, name) for agent, entry in table.items() for name in entry["options"]]
    unregistered = sorted({use.agent for use in uses()} - set(REGISTRY))
    used_agents = [agent for agent, entry in table.items() if entry["runs"]]
    set_fields = [(a, n) for a, n in fields if table[a]["options"][n]["use"] == "set"]
    return {"agents": len(table), "option_fields": len(fields), "option_names": len({n for _, n in fields}),
            "agents_in_results": len(used_agents), "option_fields_set_in_results": len(set_fields),
            "option_names_set_in_results": len({n for _, n in set_fields}),
            "agents_in_no_result": sorted(set(table) - set(used_agents)),
            "unregistered_agents_in_results": unregistered}


def _print(table: dict[str, Any]) -> None:
    print("| agent | option | default | use | set where (env: values; * = cited in README/docs) | scripts setting a "
          "option of that name |")
    print("|---|---|---|---|---|---|")
    for agent, entry in table.items():
        if not entry["runs"]:
            print(f"| {agent} | (no committed run) | | absent | | |")
        for name, option in entry["options"].items():
            where = "; ".join(f"{source}{'*' if place['cited'] else ''} "
                              f"({', '.join(e.removeprefix('rdmp_gym/') for e in place['env_ids'])}): "
                              f"{', '.join(json.dumps(v) for v in place['values'])}"
                              for source, place in option["set"].items())
            print(f"| {agent} | {name} | {json.dumps(option['default'])} | {option['use']} | {where} | "
                  f"{', '.join(option['scripts'])} |")
        for name, sources in entry["unknown_in_results"].items():
            fixed = f"fixed at {json.dumps(entry['fixed'][name])}" if name in entry["fixed"] else "unknown"
            values = sorted({json.dumps(v) for found in sources.values() for v in found})
            print(f"| {agent} | {name} (not an option) | | {fixed} | {len(sources)} results: {', '.join(values)} | |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    add_save_argument(parser)
    args = parser.parse_args()
    table = inventory()
    _print(table)
    summary = counts(table)
    print(json.dumps(summary, indent=1))
    path = results_dir(args.save) / "agent_inventory.json"
    path.write_text(json.dumps({"counts": summary, "agents": table}, indent=1, default=str))
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
