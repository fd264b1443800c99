"""Smooth reproduction (issue 7): acceleration and jerk at 1 kHz against analytic derivatives, smooth starts
from any state, any canonical initial condition, and choosing the transient from the current state."""

import numpy as np
import pytest

from rdmp_gym import RhythmicDMP, multi_transient_demonstrations, wiping_demonstration
from rdmp_gym.synthetic.smoothness import SmoothTestSignal, finite_derivatives, motion_metrics, random_test_signal

DT = 1e-3


def _reference(style):
    fine = wiping_demonstration(style, rng=0, rate=1000, noise=0.0)
    Y = fine.truth.clean
    _, acceleration, jerk = finite_derivatives(Y, DT)
    return fine.t, (Y, acceleration, jerk)


@pytest.fixture(scope="module")
def style_fits():
    return {style: RhythmicDMP.fit(wiping_demonstration(style, rng=style)) for style in (1, 2, 3, 4)}


def test_generator_derivatives_are_exact():
    signal = random_test_signal(np.random.default_rng(3), harmonics=3)
    t = np.arange(0.0, signal.transient_length + 2 * signal.period, 1e-4)
    position, velocity, acceleration, jerk = signal.derivatives(t)
    numeric = finite_derivatives(position, 1e-4)
    inner = slice(5, -5)
    for exact, estimate in zip((velocity, acceleration, jerk), numeric, strict=True):
        assert np.max(np.abs(estimate[inner] - exact[inner])) < 2e-3 * np.max(np.abs(exact))
    np.testing.assert_allclose(velocity[0], 0.0, atol=1e-12)          # starts at rest
    np.testing.assert_allclose(acceleration[0], 0.0, atol=1e-12)


@pytest.mark.parametrize("style", [1, 2, 3, 4])
def test_default_fit_reproduces_acceleration_and_jerk(style_fits, style):
    """Issue 7 targets at 1 kHz: acceleration RMSE <= 10 % (periodic) / 15 % (transient), integrated squared
    jerk <= 2x, peak acceleration <= 1.3x, position < 0.3 % / 0.8 % of the range."""
    t, reference = _reference(style)
    Y = style_fits[style].rollout(t)
    transient = t < wiping_demonstration(style).truth.transient_length
    periodic = motion_metrics(Y, reference, DT, ~transient)
    approach = motion_metrics(Y, reference, DT, transient)
    assert periodic["position"] < 0.003 and approach["position"] < 0.008
    assert periodic["acceleration"] <= 0.10 and approach["acceleration"] <= 0.15
    assert periodic["jerk_ratio"] <= 2.0 and approach["jerk_ratio"] <= 2.0
    assert periodic["peak_acceleration_ratio"] <= 1.3 and approach["peak_acceleration_ratio"] <= 1.3


def test_paper_settings_show_the_ripple_the_defaults_remove():
    from rdmp_gym.dmp.rhythmic import PAPER_SETTINGS

    t, reference = _reference(1)
    demo = wiping_demonstration(1, rng=1)
    periodic = t >= demo.truth.transient_length
    paper = RhythmicDMP.fit(demo, **{**PAPER_SETTINGS, "method": "ridge"}).rollout(t, start_blend=False)
    assert motion_metrics(paper, reference, DT, periodic)["jerk_ratio"] > 100.0


N_GENERATOR_SIGNALS = 24


@pytest.fixture(scope="module")
def generator_signals():
    """Signals drawn in sequence from seed 0 (the first six are the ones the README's table reports)."""
    rng = np.random.default_rng(0)
    signals = []
    for _ in range(N_GENERATOR_SIGNALS):
        signal = random_test_signal(rng)
        duration = signal.transient_length + max(6 * signal.period, 5.0)
        signals.append((signal, duration, signal.demonstration(duration, noise=rng.uniform(3e-4, 5e-4), rng=rng)))
    return signals


@pytest.mark.parametrize("index", range(N_GENERATOR_SIGNALS))
def test_generator_signals(generator_signals, index):
    """Own test signals (period 0.7-2 s, 1-3 harmonics, curved transient 1-2.5 s, noise 0.3-0.5 mm at 100 Hz):
    every issue-7 target, jerk <= 2x included."""
    signal, duration, demo = generator_signals[index]
    t = np.arange(0.0, duration + 1e-9, DT)
    position, _, acceleration, jerk = signal.derivatives(t)
    Y = RhythmicDMP.fit(demo).rollout(t)
    transient = t < signal.transient_length
    periodic = motion_metrics(Y, (position, acceleration, jerk), DT, ~transient)
    approach = motion_metrics(Y, (position, acceleration, jerk), DT, transient)
    assert periodic["position"] < 0.003 and approach["position"] < 0.008
    assert periodic["acceleration"] <= 0.10 and approach["acceleration"] <= 0.15
    assert periodic["peak_acceleration_ratio"] <= 1.3 and approach["peak_acceleration_ratio"] <= 1.3
    assert periodic["jerk_ratio"] <= 2.0 and approach["jerk_ratio"] <= 2.0


def test_jerk_metric_is_exact_at_the_ends_of_the_grid():
    """The jerk of the last samples must not blow up: a reproduction equal to the reference has ratio 1, and one
    ending mid-cycle is measured like the same reproduction on a longer grid."""
    signal = random_test_signal(np.random.default_rng(1), harmonics=1)
    t = np.arange(0.0, signal.transient_length + 3.3 * signal.period, DT)
    position, _, acceleration, jerk = signal.derivatives(t)
    everywhere = np.ones(t.size, dtype=bool)
    assert motion_metrics(position, (position, acceleration, jerk), DT, everywhere)["jerk_ratio"] == \
        pytest.approx(1.0, abs=0.01)
    longer = signal.derivatives(np.arange(t.size + 50) * DT, order=0)[0]
    _, longer_acceleration, longer_jerk = finite_derivatives(longer, DT)
    on_longer = motion_metrics(position, (position, acceleration, jerk), DT, everywhere,
                               longer_acceleration[: t.size], longer_jerk[: t.size])
    assert motion_metrics(position, (position, acceleration, jerk), DT, everywhere)["jerk_ratio"] == \
        pytest.approx(on_longer["jerk_ratio"], rel=0.01)


def test_narrow_transient_functions_at_close_turns_raise_the_jerk():
    """The cause of a 2.9x jerk (issue 7): a 0.8 s pattern under a 2.2 s transient, whose last transient functions
    were narrowed to 1e-3 at the next, close turn of the spiral; the default ``turn_height`` keeps them wide."""
    rng = np.random.default_rng(0)
    for _ in range(2):
        signal = random_test_signal(rng)
        duration = signal.transient_length + max(6 * signal.period, 5.0)
        demo = signal.demonstration(duration, noise=rng.uniform(3e-4, 5e-4), rng=rng)
    t = np.arange(0.0, duration + 1e-9, DT)
    reference = tuple(signal.derivatives(t)[i] for i in (0, 2, 3))
    transient = t < signal.transient_length
    narrow = motion_metrics(RhythmicDMP.fit(demo, turn_height=1e-3).rollout(t), reference, DT, transient)
    wide = motion_metrics(RhythmicDMP.fit(demo).rollout(t), reference, DT, transient)
    assert narrow["jerk_ratio"] > 2.0 > 1.5 > wide["jerk_ratio"]


def _peak_acceleration(Y):
    return float(np.max(np.linalg.norm(np.diff(Y, 2, axis=-2), axis=-1)) / DT**2)


def test_smooth_start_from_offsets_up_to_30_cm(style_fits):
    dmp = style_fits[1]
    t = np.arange(0.0, 6.0, DT)
    demo_peak = _peak_acceleration(_reference(1)[1][0])
    rng = np.random.default_rng(0)
    directions = rng.normal(size=(6, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    for distance in (0.05, 0.3):
        for direction in directions:
            y0 = dmp.starts[0] + distance * direction
            Y = dmp.rollout(t, y0=y0)
            np.testing.assert_allclose(Y[0], y0)
            assert _peak_acceleration(Y) <= 2.0 * demo_peak
    paper = dmp.rollout(t, y0=dmp.starts[0] + 0.3 * directions[0], start_blend=False)
    assert _peak_acceleration(paper) > 10.0 * demo_peak                 # the paper's start: a spike


def test_smooth_start_from_a_moving_state(style_fits):
    dmp = style_fits[1]
    t = np.arange(0.0, 6.0, DT)
    demo_peak = _peak_acceleration(_reference(1)[1][0])
    y, yd = dmp.rollout(t, y0=dmp.starts[0] + 0.1, yd0=np.array([0.2, -0.1, 0.0]), return_velocity=True)
    np.testing.assert_allclose(yd[0], [0.2, -0.1, 0.0], atol=1e-9)
    assert _peak_acceleration(y) <= 2.0 * demo_peak


def test_any_canonical_initial_condition_is_safe():
    """phi0 anywhere in [0, 2 pi), r0 from mu to 3x the largest encoded r0, and between encoded transients:
    the rollout's peak acceleration stays <= 3x the demonstration's."""
    demos = multi_transient_demonstrations(3, rng=0)
    dmp = RhythmicDMP.fit(demos, n_transient=30)
    t = np.arange(0.0, 6.0, DT)
    demo_peak = max(_peak_acceleration(fine.truth.clean)
                    for fine in multi_transient_demonstrations(3, rng=0, rate=1000, noise=0.0))
    encoded = np.array([[s.phi0, s.r0] for s in dmp.transients])
    grid = [(phi0, r0) for phi0 in np.linspace(0.0, 2 * np.pi, 8, endpoint=False)
            for r0 in np.linspace(dmp.canonical.mu, 3.0 * encoded[:, 1].max(), 4)]
    between = [0.5 * (encoded[k] + encoded[(k + 1) % 3]) for k in range(3)]
    inits = np.array(grid + between)
    groups = ("initial:0",)
    Y = dmp.rollout_batch(inits, t, groups=groups, transient=0)
    assert np.all(np.isfinite(Y))
    peaks = np.max(np.linalg.norm(np.diff(Y, 2, axis=1), axis=-1), axis=1) / DT**2
    assert np.all(peaks <= 3.0 * demo_peak), (peaks.max(), demo_peak)


def test_mixture_fades_where_activations_are_small(style_fits):
    dmp = style_fits[1]
    phi = np.linspace(0.0, 2 * np.pi, 4001)
    for r in (60.0, 300.0):                              # far outside the encoded spiral
        f = dmp.basis.forcing(phi, np.full(phi.size, r), dmp.weights)
        assert np.max(np.abs(f)) < 0.05 * np.max(np.abs(dmp.weights))
        assert np.max(np.abs(np.diff(f, axis=0))) < 1e-2 * np.max(np.abs(dmp.weights))


def test_nearest_transient_from_the_current_state():
    demos = multi_transient_demonstrations(3, rng=0)
    dmp = RhythmicDMP.fit(demos, n_transient=30)
    t = np.arange(0.0, 4.0, 0.01)
    for k in range(3):
        y0 = dmp.starts[k] + np.array([0.01, -0.01, 0.005])
        chosen = dmp.rollout(t, y0=y0, transient="nearest")
        np.testing.assert_allclose(chosen, dmp.rollout(t, y0=y0, transient=k), atol=1e-12)
        stepper = dmp.start(0.01, y0=y0, transient="nearest")
        assert stepper.transient == k
        online = [stepper.state[0]] + [stepper.step()[0] for _ in range(t.size - 1)]
        np.testing.assert_allclose(np.array(online), chosen, atol=1e-9)
    y0 = dmp.starts[[2, 0]] + 0.01                                # each row picks its own transient
    batch = dmp.rollout_batch(np.stack([dmp.anchor, dmp.anchor]), t, groups="anchor", y0=y0, transient="nearest")
    for row, k in zip(batch, (2, 0), strict=True):
        np.testing.assert_allclose(row, dmp.rollout(t, y0=y0[[2, 0].index(k)], transient=k), atol=1e-12)
    with pytest.raises(ValueError, match="transient"):
        dmp.rollout(t, transient="closest")


def test_signal_class_is_independent_of_the_builtin_styles():
    signal = SmoothTestSignal(1.0, 1.5, np.zeros(2), np.array([[0.05, 0.0]]), np.array([[0.0, 0.05]]),
                              np.array([0.2, 0.1]), np.zeros((2, 2)))
    t = np.array([0.0, 1.5, 2.5])
    position = signal.derivatives(t, order=0)[0]
    np.testing.assert_allclose(position[0], [0.2, 0.1])
    np.testing.assert_allclose(position[1:], 0.05 * np.column_stack([np.cos(2 * np.pi * t[1:]),
                                                                     np.sin(2 * np.pi * t[1:])]), atol=1e-12)
