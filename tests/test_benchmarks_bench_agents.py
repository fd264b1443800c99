"""The learner benchmark's command line: labels, per-agent seed counts, the run cache's key, reuse of earlier
results and the code versions."""

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))
from bench_agents import (
    _cache_key,
    _cached_run,
    _code,
    _labels,
    _parse,
    _seed_counts,
    _store_run,
    code_versions,
    markdown_table,
    reusable_runs,
    run_settings,
)
from rdmp_gym.agents.training import TrainConfig


def _args(seeds: int, agent_seeds: list[str]) -> argparse.Namespace:
    return argparse.Namespace(seeds=seeds, agent_seeds=agent_seeds)


def test_agent_seeds_override_the_common_count_for_one_label():
    labels = _labels(["bbrl", "plain=cpi2", "random"])
    assert _seed_counts(_args(10, ["random=3", "plain=2"]), labels) == {"bbrl": 10, "plain": 2, "random": 3}


@pytest.mark.parametrize("item", ["sac=2", "random=0", "random=x", "random"])
def test_bad_agent_seeds_name_the_argument(item):
    with pytest.raises(SystemExit, match="--agent-seeds"):
        _seed_counts(_args(10, [item]), _labels(["bbrl", "random"]))


def test_cache_key_ignores_workers_but_not_options_or_test_contexts():
    config = TrainConfig(agent="bbrl", updates=2, rollouts=2, seed=0, workers=1)
    seeds = np.arange(3)
    assert _cache_key(config, seeds) == _cache_key(TrainConfig(agent="bbrl", updates=2, rollouts=2, seed=0,
                                                               workers=2), seeds)
    assert _cache_key(config, seeds) != _cache_key(config, np.arange(4))
    other = TrainConfig(agent="bbrl", updates=2, rollouts=2, seed=0, workers=1, options={"sigma": 0.2})
    assert _cache_key(config, seeds) != _cache_key(other, seeds)


def test_a_cached_run_written_before_a_new_default_setting_still_stands_for_its_config(tmp_path):
    """A run cached when the learner had no ``fourier_features`` (its key and options lack the setting) stands
    for a config that leaves it at its default, not for one with other options or other test contexts."""
    config = TrainConfig(agent="cpi2", updates=2, rollouts=2, seed=0, workers=1)
    seeds, path = np.arange(3), tmp_path / "cpi2-0.json"
    options = config.options.to_dict()
    old_options = {key: value for key, value in options.items() if not key.startswith("fourier")}
    _store_run(config, path, seeds, {"options": old_options, "test_means": {"success": 0.5}})
    saved = json.loads(path.read_text())
    saved["key"] = saved["key"].replace(", fourier_features=0, fourier_length=1.0", "")
    assert "fourier" not in saved["key"] and len(old_options) < len(options)
    path.write_text(json.dumps(saved))
    assert _cached_run(config, path, seeds) == {"options": old_options, "test_means": {"success": 0.5}}
    assert _cached_run(config, path, np.arange(4)) is None
    other = TrainConfig(agent="cpi2", updates=2, rollouts=2, seed=0, workers=1, options={"fourier_features": 8})
    assert _cached_run(other, path, seeds) is None


def test_code_versions_group_the_runs_by_the_commit_that_trained_them():
    runs = [{"agent": "bbrl", "seed": 0, "code": {"commit": "abc", "dirty": False}},
            {"agent": "bbrl", "seed": 1, "code": {"commit": "abc", "dirty": True}},
            {"agent": "cpi2", "seed": 0, "code": {"commit": "abc", "dirty": False}},
            {"agent": "random", "seed": 0}]
    assert code_versions(runs) == {"abc": ["bbrl-0", "cpi2-0"], "abc-dirty": ["bbrl-1"], "unrecorded": ["random-0"]}


def test_a_run_records_the_commit_and_package_versions_of_its_last_session():
    class Run:
        def read_provenance(self):
            return {"sessions": [{"rdmp_gym": {"commit": "old", "dirty": False}, "packages": {"numpy": "1"}},
                                 {"rdmp_gym": {"commit": "new", "dirty": True}, "packages": {"numpy": "2"}}]}

    assert _code(Run()) == {"commit": "new", "dirty": True, "packages": {"numpy": "2"}}


def _document(options: dict, budget: int = 4) -> dict:
    settings = {"agents": ["plain=cpi2"], "env_id": "rdmp_gym/ArmarWipe-v2", "budget": budget, "rollouts": 2,
                "val_contexts": 3, "eval_every": 1, "env_kwargs": {}, "final_test_seeds": [7, 8]}
    return {"settings": settings, "runs": [{"agent": "plain", "seed": 1, "options": options, "test_means": {}}]}


def test_earlier_runs_stand_only_for_configs_that_match_every_setting():
    config = TrainConfig(agent="cpi2", env_id="rdmp_gym/ArmarWipe-v2", updates=2, rollouts=2, seed=1, workers=1,
                         eval_episodes=3, eval_every=1)
    seeds = np.array([7, 8])
    matching = _document(config.options.to_dict())
    assert list(reusable_runs([matching], [config], ["plain"], seeds)) == [("plain", 1)]
    assert reusable_runs([matching], [config], ["other"], seeds) == {}
    assert reusable_runs([matching], [config], ["plain"], np.array([7, 9])) == {}
    assert reusable_runs([_document(config.options.to_dict(), budget=6)], [config], ["plain"], seeds) == {}
    assert reusable_runs([_document({**config.options.to_dict(), "sigma": 0.2})], [config], ["plain"], seeds) == {}


def test_the_settings_of_a_call_that_reuses_results_are_json(monkeypatch):
    monkeypatch.setattr(sys, "argv", ["bench_agents.py", "--agents", "bbrl", "--reuse", "results/a.json",
                                      "--reuse", "results/b.json"])
    settings = run_settings(_parse(), {}, {"bbrl": {}}, np.arange(2))
    assert json.loads(json.dumps(settings))["reuse"] == ["results/a.json", "results/b.json"]


def test_markdown_table_has_a_row_per_policy_with_its_episodes_to_each_level():
    entry = {"estimate": 0.5, "low": 0.25, "high": 0.75}
    rows = [{"agent": "imitation", "n": 50, "over": "contexts", "success": entry, "coverage": entry,
             "jerk_ratio": entry, "returns": entry},
            {"agent": "bbrl", "n": 3, "over": "seeds", "success": entry, "coverage": entry, "jerk_ratio": entry,
             "returns": entry}]
    levels = {"0.5": {"reached": 3, "median": 400.0}, "0.8": {"reached": 1, "median": 900.0},
              "0.9": {"reached": 0, "median": None}}
    lines = markdown_table(rows, {"agents": {"bbrl": {"episodes_to": levels}}}).splitlines()
    assert len(lines) == 4 and all(line.count("|") == 7 for line in lines)
    assert lines[3] == ("| `bbrl` (3 seeds) | 0.50 [0.25, 0.75] | 0.500 [0.250, 0.750] | 0.50 [0.25, 0.75] | "
                        "0.500 [0.250, 0.750] | 400 (3/3) / 900 (1/3) / - (0/3) |")
    assert lines[2].endswith("|  |")


def test_two_labels_of_one_learner_train_in_their_own_folders(monkeypatch, tmp_path):
    """``--agents a=bbrl b=bbrl``: the same learner and seed under two labels must not share a run folder."""
    import bench_agents

    folders = []

    class _NoEvaluator:
        def __init__(self, *args):
            pass

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            return False

    def fake_job(config, run_dir, *rest):
        folders.append(run_dir)
        return {"agent": config.agent, "seed": config.seed}

    monkeypatch.setattr(bench_agents, "Evaluator", _NoEvaluator)
    monkeypatch.setattr(bench_agents, "_run_job", fake_job)
    monkeypatch.setattr(bench_agents, "SCRATCH", tmp_path / "cache")
    configs = [TrainConfig(agent="bbrl", seed=0), TrainConfig(agent="bbrl", seed=0)]
    args = argparse.Namespace(name="labels", reuse=[], fresh=True, workers=1)
    runs = bench_agents._run_locally(configs, ["wide", "narrow"], args, tmp_path / "scratch", None, np.arange(2),
                                     np.zeros((2, 3)), np.ones(2))
    assert len(runs) == 2 and len(set(folders)) == 2
    assert {folder.name for folder in folders} == {"wide-0", "narrow-0"}
