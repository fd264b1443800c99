"""Following an external rhythm (rdmp_gym.dmp.frequency): the adaptive-frequency oscillator drives the DMP's phase."""

import numpy as np
import pytest

from rdmp_gym import RhythmicDMP, wiping_demonstration
from rdmp_gym.dmp.frequency import AdaptiveFrequencyStepper, _first_order_hold, follow_rhythm
from rdmp_gym.dmp.stopping import fit_ending
from rdmp_gym.dmp.transformation import TransformationSystem
from rdmp_gym.synthetic.demonstrations import ending_demonstration

DT = 2e-3


@pytest.fixture(scope="module")
def wiping():
    return RhythmicDMP.fit(wiping_demonstration(1, rng=0))


def partner(dmp, duration, factor, step_at, rng=0):
    """A partner's hand: the x of a circle (plus a second harmonic and 1 mm noise) whose frequency steps."""
    t = np.arange(round(duration / DT)) * DT
    omega = np.where(t < step_at, dmp.canonical.omega, factor * dmp.canonical.omega)
    psi = dmp.transients[0].phi0 + np.concatenate([[0.0], np.cumsum(omega[:-1]) * DT])
    noise = 1e-3 * np.random.default_rng(rng).standard_normal(t.size)
    return t, omega, psi, 0.05 * np.cos(psi) + 0.01 * np.cos(2.0 * psi + 0.3) + noise


@pytest.mark.parametrize(("omega", "h"), [(4.2, 2e-3), (5.5, 2.6e-3), (10.0, 1e-5), (3.0, 0.02)])
def test_closed_form_step_matches_the_matrix_exponential(omega, h):
    for mine, reference in zip(_first_order_hold(omega, h, 25.0), TransformationSystem(omega, h, 25.0)._discrete,
                               strict=True):
        np.testing.assert_allclose(mine, reference, rtol=1e-12, atol=1e-15)


def test_without_an_input_rhythm_it_is_the_plain_rollout(wiping):
    n = 2500
    out = follow_rhythm(wiping, np.zeros(n), DT)               # a constant input: the oscillator runs freely
    reference = wiping.rollout(np.arange(n + 1) * DT)[1:]
    np.testing.assert_allclose(out["y"], reference, atol=1e-12)
    np.testing.assert_allclose(out["frequency"], wiping.canonical.omega)


@pytest.mark.parametrize("factor", [1.3, pytest.param(0.7, marks=pytest.mark.slow)])   # 0.7: in the slow set
def test_locks_onto_a_frequency_step_where_the_fixed_dmp_drifts(wiping, factor):
    step_at = 6.0
    t, omega, psi, u = partner(wiping, 22.0, factor, step_at)
    out = follow_rhythm(wiping, u, DT)
    error = np.angle(np.exp(1j * (out["phase"] - psi)))
    before = error[(t > 4.0) & (t < step_at)]
    assert np.abs(before).max() < 0.15                           # in phase with the partner before the step
    late = t > step_at + 10.0
    assert np.abs(out["frequency"][late] / omega[late] - 1.0).max() < 0.02
    assert np.abs(np.angle(np.exp(1j * (error[late] - before.mean())))).max() < 0.1
    fixed = wiping.canonical.omega * t + wiping.transients[0].phi0
    assert np.abs(np.angle(np.exp(1j * (fixed - psi)))[late]).max() > 1.0
    assert np.all(np.isfinite(out["yd"]))


def test_transient_and_stop_still_work_at_another_tempo():
    dmp = fit_ending(ending_demonstration(1, rng=0))
    t, _, _, u = partner(dmp, 16.0, 1.2, 0.0)              # faster from the very start
    out = follow_rhythm(dmp, u, DT, stop_at=11.0)
    assert np.linalg.norm(out["y"][0] - dmp.transients[0].start) < 1e-3
    # the start keeps its shape in space: every sample of the first 2 s lies near the plain start's path
    plain = dmp.rollout(np.arange(0.0, 3.0, 1e-3))
    early = out["y"][t < 2.0]
    nearest = np.min(np.linalg.norm(early[:, None, :] - plain[None, ::5, :], axis=2), axis=1)
    assert nearest.max() < 5e-3
    assert np.linalg.norm(out["y"][-1] - dmp.ending.goal) < 1e-3
    assert np.linalg.norm(out["yd"][-1]) < 1e-3


def test_bad_input_is_named(wiping):
    stepper = AdaptiveFrequencyStepper(wiping, DT)
    with pytest.raises(ValueError, match="u"):
        stepper.step(np.nan)
    with pytest.raises(ValueError, match="stop_at"):
        stepper.request_stop()                                   # no ending encoded
    with pytest.raises(ValueError, match="coupling"):
        AdaptiveFrequencyStepper(wiping, DT, coupling=-1.0)
