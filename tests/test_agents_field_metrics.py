"""The aggregate metrics of Agarwal et al. 2021: IQM with stratified intervals, profiles, probability of improvement."""

import numpy as np
import pytest
from rdmp_gym.agents.field_metrics import (
    curve_intervals,
    performance_profile,
    probability_of_improvement,
    stratified_interval,
)


def test_iqm_interval_covers_the_estimate_and_narrows_with_more_runs():
    rng = np.random.default_rng(0)
    few, many = rng.normal(0.5, 0.1, (5, 20)), rng.normal(0.5, 0.1, (50, 20))
    small, large = stratified_interval(few), stratified_interval(many)
    for result in (small, large):
        assert result.low <= result.estimate <= result.high
    assert large.high - large.low < 0.6 * (small.high - small.low)
    assert abs(large.estimate - 0.5) < 0.02


def test_iqm_ignores_the_outer_quartiles():
    scores = np.array([[0.0], [0.5], [0.5], [0.5], [0.5], [0.5], [0.5], [1e6]])
    assert stratified_interval(scores).estimate == pytest.approx(0.5)


def test_stratified_resampling_keeps_every_task():
    """Two tasks with scores 0 and 1 on every run: every stratified resample has IQM 0.5 (a plain bootstrap over
    all run-task scores would not)."""
    scores = np.c_[np.zeros(6), np.ones(6)] + np.random.default_rng(1).normal(0, 1e-3, (6, 2))
    result = stratified_interval(scores)
    assert result.high - result.low < 0.01


def test_probability_of_improvement():
    better, worse = np.full((5, 3), 0.9), np.full((5, 3), 0.1)
    assert probability_of_improvement(better, worse).estimate == 1.0
    assert probability_of_improvement(worse, better).estimate == 0.0
    assert probability_of_improvement(better, better).estimate == 0.5
    rng = np.random.default_rng(2)
    x, y = rng.normal(0.6, 0.2, (10, 4)), rng.normal(0.4, 0.2, (10, 4))
    result = probability_of_improvement(x, y)
    assert 0.5 < result.estimate < 1.0 and result.low <= result.estimate <= result.high
    with pytest.raises(ValueError, match="y: expected scores on the same 4 tasks"):
        probability_of_improvement(x, y[:, :2])


def test_performance_profile_is_monotone_in_the_threshold():
    scores = np.random.default_rng(3).uniform(0, 1, (10, 8))
    profile = performance_profile(scores, np.linspace(0, 1, 11))
    assert profile[0, 0] == 1.0 and profile[-1, 0] == 0.0
    assert np.all(np.diff(profile[:, 0]) <= 0)
    assert np.all(profile[:, 1] <= profile[:, 0] + 1e-12) and np.all(profile[:, 0] <= profile[:, 2] + 1e-12)


def test_curve_intervals_shape_and_bad_input():
    curves = np.random.default_rng(4).uniform(0, 1, (6, 5))
    bands = curve_intervals(curves)
    assert bands.shape == (5, 3) and np.all(bands[:, 1] <= bands[:, 0]) and np.all(bands[:, 0] <= bands[:, 2])
    with pytest.raises(ValueError, match="curves: expected finite"):
        curve_intervals(np.array([[0.1, np.nan]]))
    with pytest.raises(ValueError, match="scores: expected scores"):
        stratified_interval(np.zeros((2, 2, 2)))
