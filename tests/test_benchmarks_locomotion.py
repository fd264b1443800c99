"""The locomotion study's bookkeeping (``benchmarks/bench_locomotion.py``) on hand-made run records: the seed-paired
differences, the env steps to a threshold, the summary, which env a step learner trains on and which run is filmed."""

import numpy as np
import pytest
from bench_locomotion import (
    RESIDUAL_LEARNERS,
    _best_run,
    _sb3_env,
    paired_differences,
    steps_to,
    summarise,
)


def _run(env: str, learner: str, seed: int, final: float, curve=(0.0, 100.0)) -> dict:
    return {"env": env, "learner": learner, "seed": seed, "final_return": final, "env_steps": 20_000,
            "seconds": 10.0 + seed,
            "curve": [{"env_steps": 10_000 * k, "return": value} for k, value in enumerate(curve)]}


def test_pairs_take_only_the_seeds_both_learners_ran_and_count_the_gains():
    runs = [_run("Swimmer-v5", "cmaes", seed, 100.0 + seed) for seed in range(4)]
    runs += [_run("Swimmer-v5", "cmaes_feedback", seed, 100.0 + seed + gain) for seed, gain in
             ((0, 5.0), (1, -2.0), (2, 7.0), (5, 50.0))]                  # seed 5 has no open-loop run
    rows = paired_differences(runs)
    assert len(rows) == 1
    row = rows[0]
    assert (row["learner"], row["baseline"], row["seeds"]) == ("cmaes_feedback", "cmaes", [0, 1, 2])
    np.testing.assert_allclose(row["differences"], [5.0, -2.0, 7.0])
    assert row["seeds_gaining"] == 2 and row["iqm_difference"]["n"] == 3


def test_steps_to_is_the_first_mark_at_the_threshold_and_none_when_never():
    curve = [{"env_steps": 0, "return": 10.0}, {"env_steps": 10_000, "return": 330.0},
             {"env_steps": 20_000, "return": 320.0}]
    assert steps_to(curve, 325.0) == 10_000
    assert steps_to(curve, 10.0) == 0
    assert steps_to(curve, 400.0) is None


def test_the_summary_counts_the_seeds_that_reach_each_threshold():
    runs = [_run("Swimmer-v5", "cmaes_near", 0, 340.0, (352.0, 340.0)),
            _run("Swimmer-v5", "cmaes_near", 1, 300.0, (300.0, 310.0))]
    (row,) = summarise(runs)
    assert row["seeds"] == [0, 1] and row["env_steps"] == [20_000]
    assert row["to_threshold"]["325"] == {"reached": 1, "of": 2, "median_env_steps": 0.0}
    assert row["seconds_per_run"] == pytest.approx(10.5)


def test_a_residual_learner_trains_on_the_residual_env_with_its_scale_and_sac_on_the_raw_env():
    assert _sb3_env("HalfCheetah-v5", "sac") == ("HalfCheetah-v5", {})
    made, keywords = _sb3_env("HalfCheetah-v5", "sac_residual_full")
    assert made == "rdmp_gym/RhythmicResidual-v0"
    assert keywords == {"env_id": "HalfCheetah-v5", "scale": RESIDUAL_LEARNERS["sac_residual_full"][1]} and \
        keywords["scale"] == 1.0


def test_the_film_is_of_the_best_learners_best_seed_never_of_the_random_control():
    runs = [_run("Swimmer-v5", "random", 0, 900.0), _run("Swimmer-v5", "cmaes", 0, 200.0),
            _run("Swimmer-v5", "cmaes", 1, 260.0), _run("Swimmer-v5", "cmaes_near", 0, 330.0),
            _run("Swimmer-v5", "cmaes_near", 1, 310.0), _run("Swimmer-v5", "sac", 0, 400.0)]
    document = {"runs": runs, "summary": summarise(runs)}
    best = _best_run(document, "Swimmer-v5")
    assert (best["learner"], best["seed"]) == ("cmaes_near", 0)        # SAC on the raw env has no DMP to film
