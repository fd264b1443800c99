"""The cycle schedule of a rhythmic DMP: cycle starts, the hand-over ramp and the path of changing parameters."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rdmp_gym import wiping_demonstration
from rdmp_gym.dmp.cycles import blend_from, cycle_starts, handover_ramp, rollout_cycles
from rdmp_gym.dmp.rhythmic import RhythmicDMP

DT = 1e-3


@pytest.fixture(scope="module")
def dmp() -> RhythmicDMP:
    return RhythmicDMP.fit(wiping_demonstration(), n_periodic=20, n_transient=10)


@pytest.fixture(scope="module")
def times(dmp: RhythmicDMP) -> np.ndarray:
    return np.arange(0.0, dmp.transients[0].length + 5.2 * dmp.period, DT)


def _changed(dmp: RhythmicDMP, count: int, cycle: int, size: float, seed: int) -> np.ndarray:
    """``[count, P]`` the fitted parameters in every cycle, changed from ``cycle`` on by a random ``size``."""
    theta = dmp.get_params()
    thetas = np.repeat(theta[None], count, axis=0)
    thetas[cycle:, : dmp.basis.n_periodic * dmp.n_dims] += size * np.random.default_rng(seed).standard_normal(
        dmp.basis.n_periodic * dmp.n_dims)
    return thetas


def test_cycle_starts_are_one_period_apart_after_the_transient(dmp, times):
    starts = cycle_starts(dmp, float(times[-1]))
    assert starts[0] == 0.0
    assert starts[1] >= dmp.transients[0].length
    np.testing.assert_allclose(np.diff(starts[1:]), dmp.period, rtol=1e-9)
    assert starts[-1] <= times[-1] - 0.5 * dmp.period
    faster = cycle_starts(dmp, float(times[-1]), tempo=2.0 * dmp.canonical.tempo)
    np.testing.assert_allclose(np.diff(faster[1:]), 0.5 * dmp.period, rtol=1e-9)


@pytest.mark.parametrize("tempo", [0.6, 1.0, 1.7])
def test_at_any_tempo_the_cycles_start_at_the_phase_crossings_right_after_the_transient(dmp, tempo):
    duration = dmp.transients[0].length + 6.0 * dmp.period
    starts = cycle_starts(dmp, duration, tempo=tempo)
    period, transient_end = dmp.period / tempo, dmp.transients[0].length / tempo
    turns = starts[1:] / period                                   # the canonical phase's turns since the start
    np.testing.assert_allclose(turns, np.round(turns), atol=1e-9)
    assert transient_end <= starts[1] < transient_end + period   # the first crossing after the transient, none skipped
    np.testing.assert_allclose(np.diff(starts[1:]), period, rtol=1e-9)
    assert starts[-1] <= duration - 0.5 * period < starts[-1] + period


def test_the_hand_over_window_is_a_share_of_the_period_at_the_rollouts_tempo(dmp):
    t = np.arange(0.0, 2.0 * (dmp.transients[0].length + 4.2 * dmp.period), DT)
    starts = cycle_starts(dmp, float(t[-1]), tempo=0.5)[:3]
    thetas = _changed(dmp, len(starts), 1, 0.05, seed=4)
    path = rollout_cycles(dmp, thetas, t, starts, handover=0.5, tempo=0.5)
    after = dmp.rollout_batch(thetas[1:2], t, tempo=0.5)[0]
    own = t >= starts[1] + 0.5 * dmp.period / 0.5                 # half a period at half speed: one unit period
    assert np.array_equal(path[own], after[own])
    inside = (t > starts[1] + 0.5 * dmp.period) & (t < starts[1] + 0.9 * dmp.period)
    assert not np.allclose(path[inside], after[inside], atol=1e-6)   # still handing over there


@given(st.floats(-2.0, 5.0), st.floats(0.01, 2.0))
@settings(max_examples=50, deadline=None)
def test_the_ramp_runs_from_zero_to_one_monotonically(start, width):
    t = np.linspace(-3.0, 8.0, 2001)
    ramp = handover_ramp(t, start, width)
    assert np.all(ramp[t <= start] == 0.0) and np.all(ramp[t >= start + width] == 1.0)
    assert np.all(np.diff(ramp) >= -1e-15)


def test_the_ramp_is_c3_at_both_ends():
    t = np.linspace(-0.2, 1.2, 14001)
    ramp = handover_ramp(t, 0.0, 1.0)
    h = t[1] - t[0]
    for order in (1, 2, 3):
        derivative = np.diff(ramp, n=order) / h**order
        near_ends = (np.abs(t[:-order]) < 5 * h) | (np.abs(t[:-order] - 1.0) < 5 * h)
        # continuous: next to the ends the derivative is a small fraction of its largest value (0 outside)
        assert np.abs(derivative[near_ends]).max() < 0.01 * np.abs(derivative).max()


def test_equal_cycles_give_the_rollout_bit_for_bit(dmp, times):
    starts = cycle_starts(dmp, float(times[-1]))
    thetas = np.repeat(dmp.get_params()[None], len(starts), axis=0)
    assert np.array_equal(rollout_cycles(dmp, thetas, times, starts), dmp.rollout_batch(thetas[:1], times)[0])
    assert np.array_equal(dmp.rollout_cycles(thetas, times), dmp.rollout_batch(thetas[:1], times)[0])


@pytest.mark.parametrize("cycle", [1, 3])
def test_a_change_leaves_the_path_before_its_cycle_and_is_its_own_rollout_after(dmp, times, cycle):
    starts = cycle_starts(dmp, float(times[-1]))
    thetas = _changed(dmp, len(starts), cycle, 0.05, seed=cycle)
    path = rollout_cycles(dmp, thetas, times, starts, handover=0.25)
    before, after = dmp.rollout_batch(thetas[:1], times)[0], dmp.rollout_batch(thetas[cycle:cycle + 1], times)[0]
    up_to = times <= starts[cycle]
    assert np.array_equal(path[up_to], before[up_to])
    settled = times >= starts[cycle] + 0.25 * dmp.period
    assert np.array_equal(path[settled], after[settled])
    assert np.abs(path - before).max() > 1e-3          # the change did change the path


def _acceleration(path: np.ndarray) -> np.ndarray:
    return np.diff(path, n=2, axis=0) / DT**2


def test_the_handover_keeps_the_acceleration_continuous_and_the_jerk_bounded(dmp, times):
    starts = cycle_starts(dmp, float(times[-1]))
    thetas = _changed(dmp, len(starts), 2, 0.05, seed=7)
    smooth = rollout_cycles(dmp, thetas, times, starts, handover=0.25)
    abrupt = rollout_cycles(dmp, thetas, times, starts, handover=1e-3 / dmp.period)   # a switch within a step
    before, after = dmp.rollout_batch(thetas[:1], times)[0], dmp.rollout_batch(thetas[2:3], times)[0]
    # the largest change of acceleration from one step to the next: the rollouts' own, and across the switch
    own = max(np.abs(np.diff(_acceleration(p), axis=0)).max() for p in (before, after))
    assert np.abs(np.diff(_acceleration(smooth), axis=0)).max() < 3.0 * own
    assert np.abs(np.diff(_acceleration(abrupt), axis=0)).max() > 10.0 * own
    jerk = [np.sum(np.diff(p, n=3, axis=0) ** 2) for p in (before, after, smooth)]
    assert jerk[2] <= 1.5 * max(jerk[:2])


def test_bad_schedules_are_refused_by_name(dmp, times):
    thetas = np.repeat(dmp.get_params()[None], 3, axis=0)
    with pytest.raises(ValueError, match="starts"):
        rollout_cycles(dmp, thetas, times, np.array([0.0, 2.0, 1.0]))
    with pytest.raises(ValueError, match="handover"):
        rollout_cycles(dmp, thetas, times, np.array([0.0, 1.0, 2.0]), handover=0.0)
    with pytest.raises(ValueError, match="width"):
        handover_ramp(times, 0.0, np.nan)
    with pytest.raises(ValueError, match="before, after"):
        blend_from(np.zeros((3, 2)), np.zeros((4, 2)), np.arange(3.0), 0.0, 1.0)
    with pytest.raises(ValueError, match="duration"):
        cycle_starts(dmp, -1.0)
