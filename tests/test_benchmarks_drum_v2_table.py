"""The drumming version 2 learners' table (``benchmarks/drum_v2_table.py``): the episodes to a validation threshold
and the summary over runs."""

import pytest
from drum_v2_table import _first_reaching, summarise


def test_the_first_evaluation_at_the_threshold_counts_and_rows_without_one_are_skipped():
    log = [{"episodes": 0, "eval_success": 0.5}, {"episodes": 10, "return_mean": -1.0},
           {"episodes": 30, "eval_success": 0.8}, {"episodes": 60, "eval_success": 0.7},
           {"episodes": 90, "eval_success": 0.9}]
    assert _first_reaching(log, 0.8) == 30 and _first_reaching(log, 0.9) == 90
    assert _first_reaching(log, 0.95) is None


def test_the_summary_gives_intervals_the_runs_reaching_and_the_summed_failures():
    rows = [{"success": s, "timing_error": 0.01 * (i + 1), "jerk_ratio": 1.0, "ear": 0.2, "failures": {"timing": i},
             "episodes_to_0.8": 30 * (i + 1) if i < 3 else None, "episodes_to_0.9": None}
            for i, s in enumerate([0.6, 0.7, 0.8, 0.9])]
    table = summarise(rows)
    assert table["runs"] == 4 and table["failures"] == {"timing": 6}
    assert table["success"]["estimate"] == pytest.approx(0.75)           # the IQM of four: the middle two
    assert table["success"]["low"] <= 0.75 <= table["success"]["high"]
    assert table["episodes_to_0.8"] == {"runs": 3, "median": 60.0}
    assert table["episodes_to_0.9"] == {"runs": 0, "median": None}


def test_a_measure_no_run_has_is_none_and_the_finite_runs_alone_give_the_rest():
    """A policy whose episodes count no beat has no timing error: its NaN leaves the other runs' interval."""
    rows = [{"success": 0.0, "timing_error": t, "jerk_ratio": float("nan"), "ear": 0.0, "failures": {},
             "episodes_to_0.8": None, "episodes_to_0.9": None} for t in (0.02, float("nan"), 0.04)]
    table = summarise(rows)
    assert table["jerk_ratio"] is None
    assert table["timing_error"]["n"] == 2 and 0.02 <= table["timing_error"]["estimate"] <= 0.04
