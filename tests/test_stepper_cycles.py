"""The online integrator on a cycle schedule: DMPStepper.change_weights against rollout_cycles."""

import numpy as np
import pytest

from rdmp_gym import wiping_demonstration
from rdmp_gym.dmp.cycles import cycle_starts, handover_ramp, handover_ramp_rate, rollout_cycles
from rdmp_gym.dmp.rhythmic import RhythmicDMP
from rdmp_gym.dmp.stopping import fit_ending
from rdmp_gym.synthetic.demonstrations import ending_demonstration

DT = 1e-2


@pytest.fixture(scope="module")
def dmp() -> RhythmicDMP:
    return RhythmicDMP.fit(wiping_demonstration(), n_periodic=20, n_transient=10)


def _changed(dmp: RhythmicDMP, size: float, seed: int, periodic: bool = True) -> np.ndarray:
    """``[d, D]`` the weights with the periodic ones (or all) changed by a random ``size``."""
    weights = dmp.weights.copy()
    changing = weights[:, : dmp.basis.n_periodic] if periodic else weights
    changing += size * np.random.default_rng(seed).standard_normal(changing.shape)
    return weights


def _run(dmp: RhythmicDMP, n: int, changes: dict | None = None, coupling: np.ndarray | None = None
         ) -> tuple[np.ndarray, np.ndarray]:
    """Positions and velocities ``[n + 1, d]`` of a stepper run for ``n`` steps; ``changes``: step ->
    ``(weights, keywords of change_weights)``, requested after that many steps."""
    stepper = dmp.start(DT)
    states = [stepper.state]
    for k in range(n):
        if changes and k in changes:
            weights, keywords = changes[k]
            stepper.change_weights(weights, **keywords)
        states.append(stepper.step(coupling))
    return np.array([y for y, _ in states]), np.array([yd for _, yd in states])


def _blend_velocity(before, after, t, start, width):
    """The velocity ``[T, d]`` of ``blend_from`` of ``before = (y, yd)`` and ``after = (y, yd)`` (``[T, d]`` each)."""
    ramp, rate = handover_ramp(t, start, width)[:, None], handover_ramp_rate(t, start, width)[:, None]
    return before[1] + ramp * (after[1] - before[1]) + rate * (after[0] - before[0])


def test_the_ramp_rate_is_the_ramps_derivative():
    t = np.linspace(-0.5, 2.5, 30001)
    rate = handover_ramp_rate(t, 0.3, 1.7)
    np.testing.assert_allclose(rate, np.gradient(handover_ramp(t, 0.3, 1.7), t), atol=1e-6)
    assert np.all(rate[(t <= 0.3) | (t >= 2.0)] == 0.0) and rate.max() > 0.5


def test_the_stepper_follows_a_three_cycle_schedule(dmp):
    t = np.arange(0.0, dmp.transients[0].length + 3.2 * dmp.period, DT)
    starts = cycle_starts(dmp, float(t[-1]))[:3]
    first = _changed(dmp, 0.05, seed=1)
    second = first + (_changed(dmp, 0.05, seed=2) - dmp.weights)
    thetas = np.stack([dmp.with_weights(w).get_params() for w in (dmp.weights, first, second)])
    # the first change asked for at the start, the second once the first has handed over (before cycle 2)
    asked = int(np.ceil((starts[1] + 0.5 * dmp.period) / DT))
    y, yd = _run(dmp, t.size - 1, {0: (first, {}), asked: (second, {})})
    expected = rollout_cycles(dmp, thetas, t, starts)
    np.testing.assert_allclose(y, expected, rtol=0.0, atol=1e-9)
    assert np.abs(y - dmp.rollout(t)).max() > 1e-3                 # the changes did change the path
    window = t <= starts[2]
    velocity = _blend_velocity(dmp.rollout(t, return_velocity=True),
                               dmp.with_weights(first).rollout(t, return_velocity=True), t, starts[1],
                               0.5 * dmp.period)
    np.testing.assert_allclose(yd[window], velocity[window], rtol=0.0, atol=1e-9)


@pytest.mark.parametrize("tempo", [0.7, 1.6])
def test_at_another_tempo_the_stepper_follows_the_schedule_of_that_tempo(dmp, tempo):
    t = np.arange(0.0, (dmp.transients[0].length + 3.2 * dmp.period) / tempo, DT)
    starts = cycle_starts(dmp, float(t[-1]), tempo=tempo)[:2]
    changed = _changed(dmp, 0.05, seed=3)
    stepper = dmp.start(DT, tempo=tempo)
    assert stepper.change_weights(changed) == pytest.approx(starts[1], abs=1e-9)
    start, end = stepper.handover_window
    assert end - start == pytest.approx(0.5 * dmp.period / tempo, rel=1e-12)
    y = np.array([stepper.state[0]] + [stepper.step()[0] for _ in range(t.size - 1)])
    thetas = np.stack([dmp.get_params(), dmp.with_weights(changed).get_params()])
    np.testing.assert_allclose(y, rollout_cycles(dmp, thetas, t, starts, tempo=tempo), rtol=0.0, atol=1e-9)


def test_a_change_to_the_same_weights_changes_nothing_bit_for_bit(dmp):
    n = int(4.5 / DT)
    plain = _run(dmp, n)
    for keywords in ({}, {"at": 2.0}):
        same = _run(dmp, n, {10: (dmp.weights.copy(), keywords)})
        assert np.array_equal(same[0], plain[0]) and np.array_equal(same[1], plain[1])
    stepper = dmp.start(DT)
    assert stepper.change_weights(dmp.weights) >= dmp.transients[0].length and stepper.handover_window is None


@pytest.mark.parametrize(("asked", "at"), [(200, 3.3), (10, 0.3)])       # in a cycle; within the transient
def test_the_path_is_unchanged_before_and_the_new_weights_own_after(dmp, asked, at):
    n = int(5.0 / DT)
    new = _changed(dmp, 0.05, seed=3, periodic=False)       # the transient's weights move the settled start too
    stepper = dmp.start(DT)
    for _ in range(asked):
        stepper.step()
    assert stepper.change_weights(new, at=at, handover=0.4) == at
    assert stepper.handover_window == pytest.approx((at, at + 0.4 * dmp.period))
    changed = np.array([stepper.state[0]] + [stepper.step()[0] for _ in range(n - asked)])
    plain = _run(dmp, n)[0][asked:]
    fresh = _run(dmp.with_weights(new), n)[0][asked:]
    t = np.arange(asked, n + 1) * DT
    assert np.array_equal(changed[t <= at], plain[t <= at])
    after = t >= at + 0.4 * dmp.period
    np.testing.assert_allclose(changed[after], fresh[after], rtol=0.0, atol=1e-9)
    assert np.abs(changed - plain).max() > 1e-3
    assert np.array_equal(stepper.dmp.weights, new) and stepper.handover_window is None


def test_a_coupling_term_adds_the_same_with_and_without_a_change(dmp):
    n, coupling = int(4.5 / DT), np.array([0.02, -0.01, 0.015])
    changes = {0: (_changed(dmp, 0.05, seed=4), {})}
    plain, pushed = _run(dmp, n)[0], _run(dmp, n, coupling=coupling)[0]
    changed, changed_pushed = _run(dmp, n, changes)[0], _run(dmp, n, changes, coupling)[0]
    assert np.abs(pushed - plain).max() > 1e-4 and np.abs(changed - plain).max() > 1e-3
    np.testing.assert_allclose(changed_pushed - changed, pushed - plain, rtol=0.0, atol=1e-12)


def test_the_handover_jerk_stays_near_the_unchanged_paths(dmp):
    n, start = int(4.5 / DT), cycle_starts(dmp, 4.5)[1]
    new = _changed(dmp, 0.05, seed=1)
    t = np.arange(n + 1)[:-3] * DT
    window = (t >= start - 0.1) & (t <= start + 0.5 * dmp.period + 0.1)

    def peak_jerk(path):
        return np.abs(np.diff(path, n=3, axis=0)[window]).max() / DT**3

    own = max(peak_jerk(_run(d, n)[0]) for d in (dmp, dmp.with_weights(new)))
    smooth = peak_jerk(_run(dmp, n, {0: (new, {})})[0])
    abrupt = peak_jerk(_run(dmp, n, {0: (new, {"handover": 0.5 * DT / dmp.period})})[0])   # within a step
    assert smooth < 1.25 * own            # measured 1.09
    assert abrupt > 10.0 * own


def test_a_stop_before_or_during_a_change(dmp):
    ending = fit_ending(ending_demonstration(1, rng=1))
    t = np.arange(0.0, 7.0, DT)
    new = _changed(ending, 0.05, seed=5)
    thetas = np.stack([ending.get_params(), ending.with_weights(new).get_params()])
    for stop_at, change_first in ((3.3, True), (1.0, False)):
        stepper = ending.start(DT)
        if change_first:
            start = stepper.change_weights(new)
        path = [stepper.state[0]]
        for k in range(1, t.size):
            path.append(stepper.step()[0])
            if k == round(stop_at / DT):
                stepper.request_stop()
                if not change_first:
                    start = stepper.change_weights(new)
        expected = rollout_cycles(ending, thetas, t, np.array([0.0, start]), stop_at=stop_at)
        np.testing.assert_allclose(np.array(path), expected, rtol=0.0, atol=1e-9)
        assert np.abs(expected - ending.rollout(t, stop_at=stop_at)).max() > 1e-3


def test_bad_changes_are_refused_by_name(dmp):
    stepper = dmp.start(DT)
    for _ in range(50):
        stepper.step()
    with pytest.raises(ValueError, match=r"^weights:"):
        stepper.change_weights(dmp.weights[:, :-1])
    with pytest.raises(ValueError, match=r"^weights:"):
        stepper.change_weights(np.where(np.arange(dmp.weights.size).reshape(dmp.weights.shape) == 3, np.nan,
                                        dmp.weights))
    with pytest.raises(ValueError, match=r"^at:"):
        stepper.change_weights(dmp.weights, at=0.2)
    with pytest.raises(ValueError, match=r"^at:"):
        stepper.change_weights(dmp.weights, at=np.inf)
    for handover in (0.0, -0.5, np.nan):
        with pytest.raises(ValueError, match=r"^handover:"):
            stepper.change_weights(dmp.weights, handover=handover)
    stepper.change_weights(_changed(dmp, 0.05, seed=6))
    with pytest.raises(ValueError, match="change_weights: a change is already scheduled"):
        stepper.change_weights(_changed(dmp, 0.05, seed=7))
