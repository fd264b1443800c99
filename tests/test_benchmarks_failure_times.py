"""The failure-moment diagnostic of ``benchmarks/bench_failure_times.py`` on hand-made cost traces."""

from types import SimpleNamespace

import numpy as np
from bench_failure_times import failure_moments, path_part, tally


def _env(steps: int = 100, dt: float = 0.1, transient: float = 2.0, period: float = 1.5) -> SimpleNamespace:
    times = np.arange(steps) * dt
    return SimpleNamespace(times=times, task=SimpleNamespace(periodic=times >= transient - 1e-9),
                           dmp=SimpleNamespace(period=period))


def _trace(steps: int, charged: list[int]) -> np.ndarray:
    trace = np.zeros(steps)
    trace[charged] = 0.1
    return trace


def test_path_part_names_the_approach_and_the_wiping_cycle():
    env = _env()
    assert path_part(0, env) == "approach"
    assert path_part(19, env) == "approach"
    assert path_part(20, env) == "wiping 1"
    assert path_part(34, env) == "wiping 1"
    assert path_part(35, env) == "wiping 2"
    assert path_part(99, env) == "wiping 6"


def test_failure_moments_take_each_cause_at_its_first_charged_step():
    env = _env()
    info = {"failure_causes": ("coverage", "cup", "joint acceleration"),
            "cost_terms": {"obstacle": _trace(100, [41, 42, 60]), "joint_accel": _trace(100, [7])}}
    moments = failure_moments(info, env)
    assert moments["cup"] == {"step": 41, "part": "wiping 2"}
    assert moments["joint acceleration"] == {"step": 7, "part": "approach"}
    assert moments["coverage"] == {"step": None, "part": "whole episode"}


def test_failure_moments_of_a_cause_without_a_charged_step():
    info = {"failure_causes": ("cup",), "cost_terms": {"obstacle": np.zeros(100)}}
    assert failure_moments(info, _env())["cup"]["step"] is None


def test_tally_counts_cause_part_and_the_cups_place():
    runs = [{"failed": [
        {"cup_on_approach": True, "causes": {"cup": {"step": 3, "part": "approach"}}},
        {"cup_on_approach": False, "causes": {"cup": {"step": 50, "part": "wiping 3"},
                                              "coverage": {"step": None, "part": "whole episode"}}},
        {"cup_on_approach": False, "causes": {"cup": {"step": 30, "part": "wiping 1"}}}]}]
    counts = tally(runs)
    assert counts[("cup", "approach", "cup on approach")] == 1
    assert counts[("cup", "wiping", "cup elsewhere")] == 2
    assert counts[("coverage", "whole episode", "")] == 1
    assert sum(counts.values()) == 4
