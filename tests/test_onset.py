"""Where the rhythm starts and stops as people mark it: the first and last stroke on the working surface."""

import numpy as np
import pytest

from rdmp_gym.signals.demonstrations import to_demonstration
from rdmp_gym.signals.segmentation import segment_rhythm
from rdmp_gym.signals.segmentation.onset import rhythm_bounds
from rdmp_gym.signals.segmentation.sessions import find_sessions
from rdmp_gym.synthetic.sessions import multi_session_recording

DT, PERIOD = 0.01, 1.0


def _stroking_recording(wait: float, first_amplitude: float) -> tuple[np.ndarray, float, float]:
    """``(Y [L, 3], first stroke (s), last stroke (s))``: the hand comes down onto the table (z = 0) in 1.5 s,
    waits ``wait`` s at the stroke line, strokes figures of eight on it (3 of
    ``first_amplitude`` m along x, then 10 of 0.05 m; 0.3 of that along y; period 1 s), rests 1 s and lifts off."""
    rng = np.random.default_rng(0)
    down = 1.5
    onset = down + wait
    end = onset + 13 * PERIOD
    t = np.arange(0.0, end + 3.0, DT)
    amplitude = np.where(t < onset + 3 * PERIOD, first_amplitude, 0.05)
    stroking = (t >= onset) & (t < end)
    lift = np.clip((t - end - 1.0) / 1.0, 0.0, 1.0)
    phase = 2 * np.pi * (t - onset) / PERIOD
    x = np.where(stroking, amplitude * np.sin(phase), 0.0)
    y = np.where(stroking, 0.3 * amplitude * np.sin(2 * phase), 0.0) + 0.1 * lift
    z = 0.2 * (1.0 - np.clip(t / down, 0.0, 1.0)) ** 2 + 0.2 * lift ** 2
    Y = np.column_stack([x, y, z]) + 0.0005 * rng.standard_normal((t.size, 3))
    return Y, onset, end


@pytest.mark.parametrize("wait", [0.0, 2.0])
def test_waiting_at_the_stroke_line_is_no_stroke(wait: float) -> None:
    Y, onset, end = _stroking_recording(wait, 0.05)
    first, last = round((onset + 4 * PERIOD) / DT), round((end - 2 * PERIOD) / DT)
    found_onset, found_stop = rhythm_bounds(Y, first, last, PERIOD, DT)
    assert abs(found_onset * DT - onset) < 0.3              # the first stroke, not the arrival 2 s before
    assert abs(found_stop * DT - end) < 0.3                 # the last stroke, not the lift-off 1 s after


def test_larger_first_strokes_on_the_surface_count() -> None:
    Y, onset, end = _stroking_recording(2.0, 0.12)          # 3 strokes more than twice the size of the rest
    first, last = round((onset + 5 * PERIOD) / DT), round((end - 2 * PERIOD) / DT)
    found_onset, _ = rhythm_bounds(Y, first, last, PERIOD, DT)
    assert abs(found_onset * DT - onset) < 0.5              # faster strokes reach the speed share a little early


def test_segmentation_reports_the_first_stroke_after_a_wait() -> None:
    Y, onset, end = _stroking_recording(2.0, 0.05)
    seg = segment_rhythm(to_demonstration(np.arange(Y.shape[0]) * DT, Y))
    assert seg.rhythm_onset <= seg.rhythm_start and seg.rhythm_end <= seg.rhythm_stop
    assert abs(seg.rhythm_onset - onset) < 0.5 and abs(seg.rhythm_stop - end) < 0.5


# Slow set: each case is a 3-session search (wiping 5 CPU s, kitchen and long 13 s each). The default set checks
# these bounds on generated wiping sessions in test_sessions.py::test_each_session_is_found_with_its_onset_and_stop
# (seed 1, the recording that file's other tests search), and the onset and stop of single kitchen and long
# recordings in test_sessions.py::test_onset_and_stop_surround_the_full_size_rhythm.
@pytest.mark.slow
@pytest.mark.parametrize("kind", ["wiping", "kitchen", "long"])
def test_generated_sessions_start_and_stop_with_their_truth(kind: str) -> None:
    made = multi_session_recording(3, kind, rng=np.random.default_rng(0))
    sessions = find_sessions(to_demonstration(made.recording.t, made.recording.Y))
    assert len(sessions) == len(made.sessions)
    for session, truth in zip(sessions, made.sessions, strict=True):
        assert abs(session.rhythm_onset - truth.onset) < 0.8       # the growth starts while the hand approaches
        assert abs(session.rhythm_stop - truth.stop) < 0.5


def test_a_rhythm_from_the_first_sample_starts_there() -> None:
    Y, onset, _ = _stroking_recording(0.0, 0.05)
    Y = Y[round(onset / DT):]                                # no approach: stroking from the first sample
    found_onset, _ = rhythm_bounds(Y, round(3 * PERIOD / DT), round(9 * PERIOD / DT), PERIOD, DT)
    assert found_onset * DT < 0.3
