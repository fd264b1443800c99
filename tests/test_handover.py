"""The hand-over from the transient to the periodic pattern: the C2 test joins, the worst-window measure, the
off-path probe, and the placement of the fade between the families."""

import numpy as np
import pytest

from rdmp_gym import RhythmicDMP
from rdmp_gym.dmp import FADE_AFTER_T
from rdmp_gym.smoothness import (
    draw_test_demonstrations,
    finite_derivatives,
    off_path_peak_ratio,
    off_path_starts,
    peak_acceleration,
    random_test_signal,
    worst_window_error,
)

DT = 1e-3


def test_quintic_join_is_c2_at_T():
    """With join='quintic' the start meets the orbit at T with equal position, velocity and acceleration."""
    signal = random_test_signal(np.random.default_rng(3), join="quintic")
    T = signal.transient_length
    before = signal.derivatives(np.array([T - 1e-9]))
    after = signal.derivatives(np.array([T + 1e-9]))
    for order in range(3):
        assert np.allclose(before[order], after[order], atol=1e-5), order
    start = signal.derivatives(np.array([0.0]))
    assert np.allclose(start[1], 0.0) and np.allclose(start[2], 0.0)          # from rest


def test_worst_window_finds_a_local_fault():
    """A 0.1 s burst in an otherwise exact reproduction: the window covers it and its error is the burst's RMS
    over a 0.2 s window relative to the whole signal's RMS."""
    t = np.arange(0.0, 4.0, DT)
    truth = np.stack([np.sin(2 * np.pi * t), np.cos(2 * np.pi * t)], axis=1)
    Ydd = truth.copy()
    burst = (t >= 2.0) & (t < 2.1)
    Ydd[burst, 0] += 1.0
    error, at = worst_window_error(Ydd, truth, DT)
    assert 1.9 <= at <= 2.0 + 1e-9
    assert error == pytest.approx(np.sqrt(0.5), rel=0.02)          # RMS of truth is 1
    with pytest.raises(ValueError, match="Ydd"):
        worst_window_error(Ydd[:100], truth, DT)


def test_off_path_starts_leave_the_encoded_path():
    demo = draw_test_demonstrations(np.random.default_rng(0), 1, join="quintic")[0][1]
    dmp = RhythmicDMP.fit(demo)
    starts = off_path_starts(dmp)
    encoded = np.array([dmp.transients[0].phi0, dmp.transients[0].r0])
    assert starts.shape == (32, 2) and not np.any(np.all(np.isclose(starts, encoded), axis=1))
    ratio = off_path_peak_ratio(dmp, float(peak_acceleration(demo.Y, 1.0 / 100.0)), duration=2.0)
    assert np.isfinite(ratio) and ratio > 0.0


def test_handover_placement_is_checked():
    demo = draw_test_demonstrations(np.random.default_rng(0), 1, join="quintic")[0][1]
    with pytest.raises(ValueError, match="handover"):
        RhythmicDMP.fit(demo, handover="late")


def test_fade_after_T_cuts_the_handover_error():
    """On the first C2 join (2 harmonics, T about 1 s) the fade after T lowers the transient's acceleration error
    and the worst 0.2 s window against the paper's placement (measured 29 % -> 10 %, 49 % -> 16 %)."""
    signal, demo = draw_test_demonstrations(np.random.default_rng(0), 1, join="quintic")[0]
    t = np.arange(0.0, demo.duration + 1e-9, DT)
    _, _, acceleration, _ = signal.derivatives(t)
    transient = t < signal.transient_length
    scale = np.sqrt(np.mean(np.sum(acceleration[transient] ** 2, axis=1)))
    errors = {}
    for name, settings in {"before": {}, "after": FADE_AFTER_T}.items():
        Ydd = finite_derivatives(RhythmicDMP.fit(demo, **settings).rollout(t), DT)[1]
        rms = np.sqrt(np.mean(np.sum((Ydd - acceleration)[transient] ** 2, axis=1)))
        errors[name] = (rms / scale, worst_window_error(Ydd, acceleration, DT)[0])
    assert errors["after"][0] <= 0.12 < errors["before"][0]
    assert errors["after"][1] < 0.2 < errors["before"][1]
