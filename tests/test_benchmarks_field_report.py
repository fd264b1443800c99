"""The field report of the learner benchmark: episodes to each validation target, the best learner, the ceiling."""

import copy
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))
import field_report
from field_report import episodes_to, failure_counts, field_summary, hardest_contexts, write


def _run(agent, seed, successes, rate):
    curve = [{"episodes": 100 * i, "eval_success": s} for i, s in enumerate(successes)]
    test = np.random.default_rng(seed).uniform(size=20) < rate
    return {"agent": agent, "seed": seed, "curve": curve,
            "test": {"success": test.tolist(), "coverage": (0.9 + 0.1 * test).tolist()}}


def _document():
    runs = [_run("good", s, [0.2, 0.6, 0.9, 0.95], 0.9) for s in range(4)]
    runs += [_run("weak", s, [0.2, 0.3, 0.5, 0.5], 0.4) for s in range(4)]
    return {"runs": runs, "baselines": {"imitation": {"success": [0.0, 1.0, 0.0, 0.0]}},
            "settings": {"final_test_seeds": list(range(100, 120)), "env_id": "not-a-solved-env"}}


@pytest.fixture(scope="module")
def summary_of_document():
    """``field_summary(_document())`` (its bootstrap intervals cost ~2 CPU s, seeded), computed once for the tests that
    read it, ``write``'s included."""
    return field_summary(_document())


def test_episodes_to_a_target_is_the_first_evaluation_that_reaches_it():
    curve = [{"episodes": 0, "eval_success": 0.1}, {"episodes": 50, "eval_success": 0.8},
             {"episodes": 100, "eval_success": None}, {"episodes": 150, "eval_success": 0.95}]
    assert episodes_to(curve, 0.5) == 50 and episodes_to(curve, 0.9) == 150 and episodes_to(curve, 0.99) is None


def test_field_summary_ranks_the_learners_and_counts_the_seeds_that_reach_each_target(tmp_path, summary_of_document,
                                                                                     monkeypatch):
    def computed(document):                    # write's summary of the document is the module's one
        assert document == _document()
        return copy.deepcopy(summary_of_document)

    monkeypatch.setattr(field_report, "field_summary", computed)
    summary = write(_document(), tmp_path, "bench", "title")
    good, weak = summary["agents"]["good"], summary["agents"]["weak"]
    assert summary["best"] == "good" and summary["ceiling"] is None
    assert good["episodes_to"]["0.9"] == {"reached": 4, "median": 200.0}
    assert weak["episodes_to"]["0.9"]["reached"] == 0 and weak["episodes_to"]["0.5"]["median"] == 200.0
    assert good["test_success"]["estimate"] > weak["test_success"]["estimate"]
    assert summary["improvement"]["weak"]["estimate"] > 0.5
    assert summary["agents"]["weak"]["improvement"]["good"]["estimate"] < 0.5
    assert summary["agents"]["good"]["improvement"] == summary["improvement"]
    assert summary["imitation_success"] == 0.25
    assert (tmp_path / "bench_field.json").is_file() and (tmp_path / "bench_field.png").stat().st_size > 10_000
    assert summary_of_document["agents"]["good"]["curve"][-1][0] == 0.95


def test_hardest_contexts_are_those_most_runs_fail_hardest_first():
    success = np.array([[1, 0, 0, 1], [1, 0, 1, 0], [1, 0, 0, 1]], dtype=float)
    contexts = [[0.0, 1.0], [0.5, 0.25], [0.125, 0.0], [1.0, 1.0]]
    hardest = hardest_contexts(success, [10, 11, 12, 13], contexts)
    assert [h["index"] for h in hardest] == [1, 2]
    assert hardest[0] == {"index": 1, "seed": 11, "success": 0.0, "context": [0.5, 0.25]}
    assert hardest_contexts(success, [10, 11, 12, 13], None)[1]["context"] is None


def test_failure_counts_add_each_missed_criterion_over_the_runs_that_name_them(summary_of_document):
    runs = [{"test": {"failures": ["", "cup", "cup+coverage"]}}, {"test": {"failures": ["coverage", "", ""]}},
            {"test": {"success": [True]}}]
    counts = failure_counts(runs)
    assert counts == {"runs": 2, "failures": 3, "causes": {"cup": 2, "coverage": 2}}
    assert failure_counts([]) == {"runs": 0, "failures": 0, "causes": {}}
    assert summary_of_document["agents"]["good"]["failure_causes"]["runs"] == 0


def test_by_kind_counts_success_and_causes_per_kind_of_test_context():
    from field_report import by_kind

    runs = [{"test": {"success": [1, 0, 0, 1], "failures": ["", "cup", "coverage+cup", ""]}},
            {"test": {"success": [1, 1, 0, 0], "failures": ["", "", "coverage", "jerk"]}}]
    rows = by_kind(runs, ["a", "b", "b", "a"])
    assert rows["a"] == {"contexts": 2, "success": 0.75, "failures": 1, "causes": {"jerk": 1}}
    assert rows["b"]["contexts"] == 2 and rows["b"]["success"] == 0.25 and rows["b"]["failures"] == 3
    assert rows["b"]["causes"] == {"coverage": 2, "cup": 2}
