"""Each concept of the core in one home: one period estimator for every segmentation, one fading gate for the
start and the stop (no module reading another's private names: test_core_layout.py)."""

import numpy as np
import pytest

from rdmp_gym import Fading, segment, wiping_demonstration
from rdmp_gym.dmp.ending import StopFading
from rdmp_gym.signals.demonstrations import to_demonstration
from rdmp_gym.signals.segmentation import PERIOD_METHODS, estimate_period, segment_rhythm
from rdmp_gym.synthetic.demonstrations import realistic_recording


@pytest.mark.parametrize("method", PERIOD_METHODS)
def test_every_period_method_finds_a_coarse_period_of_a_demonstration(method: str) -> None:
    demo = wiping_demonstration(1, rng=0)
    assert estimate_period(demo, method) == pytest.approx(demo.truth.period, rel=0.15)


def test_demonstrations_and_recordings_refine_the_one_estimator() -> None:
    demo = wiping_demonstration(3, rng=0)            # autocorrelation: coarse 1.599 s, refined to the truth
    assert segment(demo).period == pytest.approx(demo.truth.period, rel=0.01)
    recording = realistic_recording("kitchen", rng=np.random.default_rng(0))
    rhythm = to_demonstration(recording.t, recording.Y)
    with pytest.raises(ValueError, match="no periodicity"):    # the rhythm runs for part of the recording only
        estimate_period(rhythm, "autocorrelation")
    assert estimate_period(rhythm, "local_fit") == pytest.approx(recording.truth.period, rel=0.15)
    assert segment_rhythm(rhythm).period == pytest.approx(recording.truth.period, rel=0.02)


def test_an_unknown_period_method_is_refused_by_name() -> None:
    with pytest.raises(ValueError, match="method"):
        estimate_period(wiping_demonstration(1, rng=0), "fft")


def test_the_stop_gates_are_the_start_gates_mirrored() -> None:
    r = np.linspace(0.0, 3.0, 601)
    start, stop = Fading(0.7, 0.9, k=4, delta=1e-3), StopFading(0.9, 0.7, k=4, delta=1e-3)
    assert stop.v_tilde == start.v_tilde
    np.testing.assert_array_equal(stop.stop_gate(r), start.periodic_gate(r))
    np.testing.assert_array_equal(stop.periodic_gate(r), start.transient_gate(r))

