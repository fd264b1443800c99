"""Tests for rdmp_gym.signals.segmentation: period, transient length, anchor and phase shift.

Measured with the default noise (0.3 mm at 100 Hz, 20 seeds per style): period error < 1e-4
relative, anchor error < 0.04 mm, transient length 0.10-0.25 s early (the last part of a C^3
approach deviates from the pattern by less than the noise) and never more than 0.05 s late.
"""

from __future__ import annotations

import numpy as np
import pytest

from rdmp_gym.signals.demonstrations import Demonstration
from rdmp_gym.signals.segmentation import Segmentation, phase_shift, segment
from rdmp_gym.synthetic.demonstrations import multi_transient_demonstrations, wiping_demonstration

STYLES = (1, 2, 3, 4)
SEEDS = (0, 1, 2)


def _true_segmentation(demo: Demonstration) -> Segmentation:
    truth = demo.truth
    return Segmentation(truth.period, truth.transient_length, truth.anchor)


def _deviation_after(demo: Demonstration, transient_length: float) -> float:
    """Largest distance (m) of the clean signal after ``transient_length`` from its periodic part."""
    clean, step = demo.truth.clean, 2 * round(demo.truth.period / demo.dt)
    first = round(transient_length / demo.dt)
    return float(np.abs(clean[first:-step] - clean[first + step:]).max())


def _wrap(shift: float, period: float) -> float:
    """``shift`` mapped into ``[-period / 2, period / 2)``."""
    return (shift + 0.5 * period) % period - 0.5 * period


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("style", STYLES)
def test_wiping_styles(style: int, seed: int) -> None:
    demo = wiping_demonstration(style, rng=seed)
    seg, truth = segment(demo), demo.truth
    assert abs(seg.period - truth.period) < 5e-4 * truth.period
    assert -0.30 <= seg.transient_length - truth.transient_length <= 0.05
    assert _deviation_after(demo, seg.transient_length) < 1e-3  # periodic within ~3 noise std
    np.testing.assert_allclose(seg.anchor, truth.anchor, atol=2e-4)
    assert seg.anchor.shape == (3,)


@pytest.mark.parametrize("style", STYLES)
def test_noise_free_demonstrations_are_segmented_tightly(style: int) -> None:
    demo = wiping_demonstration(style, noise=0.0)
    seg, truth = segment(demo), demo.truth
    assert abs(seg.period - truth.period) < 1e-6 * truth.period
    assert abs(seg.transient_length - truth.transient_length) <= 0.05
    np.testing.assert_allclose(seg.anchor, truth.anchor, atol=1e-8)


def _sinusoid_sum(period: float, transient_length: float, blend_order: int, *, seed: int,
                  noise: float = 3e-3, duration: float = 12.0) -> Demonstration:
    """1-D: a three-harmonic pattern entered from rest at 2.0 through a smoothstep of C^(order-1)."""
    t = np.arange(round(duration * 100) + 1) / 100.0
    angle = 2.0 * np.pi * t / period
    pattern = 0.8 * np.sin(angle) + 0.3 * np.cos(2.0 * angle + 0.5) + 0.1 * np.sin(3.0 * angle)
    u = np.clip(t / transient_length, 0.0, 1.0)
    step = {2: u * u * (3.0 - 2.0 * u), 3: u**3 * (10.0 - 15.0 * u + 6.0 * u * u)}[blend_order]
    y = np.where(u >= 1.0, pattern, 2.0 + step * (pattern - 2.0))
    return Demonstration(t, y + noise * np.random.default_rng(seed).standard_normal(t.size))


@pytest.mark.parametrize(("period", "transient_length", "blend_order", "early"), [
    (1.3, 1.7, 2, 0.15), (0.9, 3.0, 2, 0.15), (2.1, 2.5, 3, 0.3), (1.0, 1.2, 3, 0.3),
])
def test_one_dimensional_sinusoid_sums(period, transient_length, blend_order, early) -> None:
    for seed in (0, 1):
        seg = segment(_sinusoid_sum(period, transient_length, blend_order, seed=seed))
        assert abs(seg.period - period) < 5e-4 * period
        assert -early <= seg.transient_length - transient_length <= 0.05
        assert abs(seg.anchor[0]) < 1e-3 and seg.anchor.shape == (1,)


def test_invariant_to_units_and_time_origin() -> None:
    demo = wiping_demonstration(2, rng=4)
    seg = segment(demo)
    scale = np.array([1000.0, 1.0, 0.01])
    moved = Demonstration(demo.t + 5.0, demo.Y * scale)
    other = segment(moved)
    assert other.transient_length == pytest.approx(seg.transient_length, abs=1e-9)
    assert other.period == pytest.approx(seg.period, rel=1e-7)
    np.testing.assert_allclose(other.anchor, seg.anchor * scale, rtol=1e-6, atol=1e-12)


def test_known_period_is_used_as_given() -> None:
    demo = wiping_demonstration(3, rng=1)
    seg = segment(demo, period=demo.truth.period)
    assert seg.period == demo.truth.period
    assert -0.30 <= seg.transient_length - demo.truth.transient_length <= 0.05


def test_phase_shift_recovers_entrance_times() -> None:
    """With the true transient lengths, ps is the difference of the entrance times."""
    for style in STYLES:
        demos = multi_transient_demonstrations(3, rng=style, style=style)
        truths = [demo.truth for demo in demos]
        period = truths[0].period
        true_segs = [_true_segmentation(demo) for demo in demos]
        for k in (1, 2):
            shift = phase_shift(demos[0], true_segs[0], demos[k], true_segs[k])
            expected = truths[k].entrance_time - truths[0].entrance_time
            assert 0.0 <= shift < period
            assert abs(_wrap(shift - expected, period)) < 0.002


def test_phase_shift_with_estimated_segmentations() -> None:
    """With estimated transient lengths T^, the shift refers to T^: it moves by T^ - T."""
    demos = multi_transient_demonstrations(3, rng=5)
    segs = [segment(demo) for demo in demos]
    truths = [demo.truth for demo in demos]
    period = truths[0].period
    for k in (1, 2):
        shift = phase_shift(demos[0], segs[0], demos[k], segs[k])
        expected = ((truths[k].entrance_time + segs[k].transient_length - truths[k].transient_length)
                    - (truths[0].entrance_time + segs[0].transient_length
                       - truths[0].transient_length))
        assert abs(_wrap(shift - expected, period)) < 0.002


def test_phase_shift_properties() -> None:
    first, second = multi_transient_demonstrations(2, rng=1)
    seg_first, seg_second = _true_segmentation(first), _true_segmentation(second)
    period = seg_first.period
    assert abs(_wrap(phase_shift(first, seg_first, first, seg_first), period)) < 1e-6
    forward = phase_shift(first, seg_first, second, seg_second)
    backward = phase_shift(second, seg_second, first, seg_first)
    assert abs(_wrap(forward + backward, period)) < 1e-3
    lifted = Demonstration(second.t, second.Y + np.array([0.2, -0.1, 0.05]))
    assert abs(_wrap(phase_shift(first, seg_first, lifted, seg_second) - forward, period)) < 1e-6


def test_too_few_periods_after_the_transient() -> None:
    demo = wiping_demonstration(1, rng=0, duration=5.0)
    with pytest.raises(ValueError, match=r"^demo: only 2\.\d periods after the transient, need at "
                                         r"least 3"):
        segment(demo, min_periods=3)
    short = Demonstration(demo.t[:300], demo.Y[:300])
    with pytest.raises(ValueError, match=r"^demo: "):
        segment(short)


@pytest.mark.parametrize("period", [0.0, -1.5, np.nan, np.inf])
def test_bad_period(period: float) -> None:
    demo = wiping_demonstration(1)
    with pytest.raises(ValueError, match=r"^period:"):
        segment(demo, period=period)
    seg = segment(demo)
    with pytest.raises(ValueError, match=r"^period:"):
        phase_shift(demo, seg, demo, seg, period=period)


@pytest.mark.parametrize("signal", ["white", "random_walk", "chirp", "constant", "ramp"])
def test_no_periodicity(signal: str) -> None:
    t = np.arange(1001) / 100.0
    rng = np.random.default_rng(0)
    y = {"white": rng.standard_normal(t.size), "random_walk": np.cumsum(rng.standard_normal(t.size)),
         "chirp": np.sin(2.0 * np.pi * (0.3 * t + 0.1 * t * t)), "constant": np.ones(t.size),
         "ramp": t}[signal]
    with pytest.raises(ValueError, match=r"^demo: no periodicity found"):
        segment(Demonstration(t, y))


def test_bad_arguments() -> None:
    demo = wiping_demonstration(1)
    with pytest.raises(TypeError, match="demo"):
        segment(demo.Y)
    for kwargs, name in (({"min_periods": 0.5}, "min_periods"), ({"min_periods": -1}, "min_periods"),
                         ({"n_harmonics": 0}, "n_harmonics"), ({"margin": 0.0}, "margin")):
        with pytest.raises(ValueError, match=rf"^{name}:"):
            segment(demo, **kwargs)
    seg = segment(demo)
    flat = Demonstration(demo.t, demo.Y[:, :2])
    with pytest.raises(ValueError, match=r"^other:"):
        phase_shift(demo, seg, flat, seg)
    with pytest.raises(TypeError, match="other_seg"):
        phase_shift(demo, seg, demo, (1.5, 2.0))
    late = Segmentation(seg.period, demo.duration - 0.5, seg.anchor)
    with pytest.raises(ValueError, match=r"^other: the periodic part is shorter"):
        phase_shift(demo, seg, demo, late)
    with pytest.raises(ValueError, match="transient_length"):
        Segmentation(1.5, -0.1, np.zeros(3))
