"""Realistic recordings, their segmentation and the whole-recording fit."""

import json

import numpy as np
import pytest
from rdmp_gym.agents.cli import main as cli_main

from rdmp_gym.recordings.recording_fit import _cycle_cuts, constant_columns, fit_recording, recording_report
from rdmp_gym.signals.demonstrations import to_demonstration
from rdmp_gym.signals.filters import despike
from rdmp_gym.signals.segmentation import segment_ending, segment_rhythm
from rdmp_gym.synthetic.demonstrations import realistic_recording


def _recording(kind: str, seed: int = 0):
    recording = realistic_recording(kind, rng=np.random.default_rng(seed))
    return recording, to_demonstration(recording.t, recording.Y)


def test_generator_is_seeded_and_has_the_hard_cases() -> None:
    a = realistic_recording("kitchen", rng=np.random.default_rng(5))
    b = realistic_recording("kitchen", rng=np.random.default_rng(5))
    np.testing.assert_array_equal(a.Y, b.Y)
    truth = a.truth
    steps = np.diff(a.t)
    assert steps.max() > 1.5 * steps.min()                              # an uneven clock
    assert truth.rhythm_start > 6.0                                     # a long approach (with a pause)
    assert np.max(np.abs(a.Y - truth.clean)) > 0.009                    # outliers of 1-3 cm
    rhythm = (a.t > truth.rhythm_start) & (a.t < truth.rhythm_end)
    drift = np.ptp(truth.working_point[rhythm, :2], axis=0).max()
    assert drift > 0.005                                                # the working point drifts
    rest = a.t > truth.rest_time
    assert 1e-4 < np.ptp(truth.clean[rest], axis=0).max() < 0.01        # the rest drifts slowly


def test_despike_removes_outliers_and_keeps_the_motion() -> None:
    recording, _ = _recording("wiping")
    cleaned = despike(recording.Y)
    assert np.max(np.abs(cleaned - recording.truth.clean)) < 0.005
    smooth = np.sin(np.linspace(0.0, 6.0, 500))[:, None]
    np.testing.assert_array_equal(despike(smooth), smooth)


@pytest.mark.parametrize("kind", ["wiping", "kitchen", "long"])
def test_segment_rhythm_finds_period_start_end_and_rest(kind: str) -> None:
    recording, demo = _recording(kind, seed=1)
    truth = recording.truth
    seg = segment_rhythm(demo)
    assert seg.period == pytest.approx(truth.period, rel=0.05)
    assert abs(seg.rhythm_start - truth.rhythm_start) < 0.3 * truth.period
    assert abs(seg.rhythm_end - truth.rhythm_end) < 0.75 * truth.period
    assert seg.rest_time is not None and abs(seg.rest_time - truth.rest_time) < 0.5
    hinted = segment_rhythm(demo, period=truth.period, start=truth.rhythm_start, end=truth.rhythm_end)
    assert hinted.rhythm_start == pytest.approx(truth.rhythm_start, abs=demo.dt)
    assert hinted.period == truth.period


def test_segment_ending_comes_to_rest_on_a_drifting_rest() -> None:
    recording, demo = _recording("wiping")
    seg = segment_ending(demo)
    assert abs(seg.rest_time - recording.truth.rest_time) < 0.5


def test_fit_recording_meets_the_accuracy_and_smoothness_targets() -> None:
    _, demo = _recording("long")
    result = fit_recording(demo)
    report = recording_report(demo, result)
    assert result.dmp.sweep is not None and result.dmp.ending is not None
    assert result.dmp.transients[0].length == pytest.approx(result.segmentation.rhythm_start)
    assert report["error_ratio"] < 1.5
    assert report["start_error"] < 0.01 and report["rest_error"] < 0.01
    assert report["acceleration_ratio"] < 1.5


# the shortest, the longest and three moves in the default set; the lengths between them in the slow set
BETWEEN = [pytest.param(approach, marks=pytest.mark.slow) for approach in [(2.5,), (5.0,), (8.0,)]]


@pytest.mark.parametrize("approach", [(1.0,), *BETWEEN, (15.0,), (4.0, 4.0, 7.0)])
def test_the_fit_stays_smooth_for_any_approach_length(approach) -> None:
    """Approaches of 1 s to 15 s, one move or three (the slow part is the anchor's sweep, not a long transient): the
    reproduction's peak acceleration stays within 1.5x the smoothed recording's, the start and the rest within
    1 cm."""
    recording = realistic_recording("wiping", rng=np.random.default_rng(3), approach=approach, n_periods=6)
    demo = to_demonstration(recording.t, recording.Y)
    result = fit_recording(demo)
    report = recording_report(demo, result)
    assert abs(result.segmentation.rhythm_start - recording.truth.rhythm_start) < 0.4 * recording.truth.period
    assert report["acceleration_ratio"] < 1.5 and report["error_ratio"] < 1.5
    assert report["start_error"] < 0.01 and report["rest_error"] < 0.01


def test_bad_input_names_the_argument() -> None:
    with pytest.raises(ValueError, match="kind"):
        realistic_recording("sanding", rng=np.random.default_rng(0))
    with pytest.raises(TypeError, match="rng"):
        realistic_recording("wiping", rng=0)
    with pytest.raises(ValueError, match="approach"):
        realistic_recording("wiping", rng=np.random.default_rng(0), approach=(2.0, -1.0))
    _, demo = _recording("wiping")
    with pytest.raises(ValueError, match="start"):
        segment_rhythm(demo, start=-1.0)
    with pytest.raises(ValueError, match="end"):
        segment_rhythm(demo, start=5.0, end=4.0)
    flat = to_demonstration(np.arange(500) * 0.01, np.zeros((500, 3)))
    with pytest.raises(ValueError, match="rhythm"):
        segment_rhythm(flat)


def test_cycles_are_cut_at_the_phase_that_holds_the_most_whole_cycles() -> None:
    """2.4 periods that begin just after an upward crossing of the mean hold one whole cycle from there, two from
    another phase: the cycle-to-cycle variation of a short rhythm can be measured."""
    t = np.arange(0.05, 2.45, 0.01)
    rhythmic = np.column_stack([np.sin(2.0 * np.pi * t), 0.5 * np.cos(2.0 * np.pi * t)])
    cuts = _cycle_cuts(t, rhythmic, 1.0, t[0], t[-1])
    assert cuts.size == 3
    assert np.allclose(np.diff(t[cuts]), 1.0, atol=0.02)


def test_report_without_a_final_rest_has_no_rest_error() -> None:
    recording, demo = _recording("kitchen")
    keep = demo.t - demo.t[0] < recording.truth.rhythm_end - 1.0
    cut = to_demonstration(demo.t[keep], demo.Y[keep], outliers=False)
    result = fit_recording(cut)
    report = recording_report(cut, result)
    assert result.segmentation.rest_time is None and result.dmp.ending is None
    assert report["rest_error"] is None
    assert report["error_ratio"] < 1.5 and report["acceleration_ratio"] < 1.5



def test_a_constant_column_is_held_by_the_anchor_and_named_in_the_report(tmp_path, capsys) -> None:
    """A height a controller holds (the same z on every row) fits beside the moving columns; the report names it."""
    recording, moving = _recording("wiping")
    held = recording.Y.copy()
    held[:, 2] = 0.8125
    demo = to_demonstration(recording.t, held)
    assert constant_columns(demo.Y) == [2] and constant_columns(moving.Y) == []
    result = fit_recording(demo)
    report = recording_report(demo, result)
    assert report["error_ratio"] < 1.5 and report["acceleration_ratio"] < 1.5
    assert np.abs(result.reproduce(np.arange(0.0, demo.duration, 0.01))[:, 2] - 0.8125).max() < 1e-9
    path = tmp_path / "held.csv"
    np.savetxt(path, np.column_stack([recording.t, held]), delimiter=",", header="t,x,y,z", comments="")
    assert cli_main(["fit", "--demo", str(path), "--out", str(tmp_path / "fit")]) == 0
    assert json.loads((tmp_path / "fit" / "report.json").read_text())["constant_columns"] == [2]
    assert "constant: dimension(s) 2" in capsys.readouterr().out
    assert constant_columns(np.column_stack([np.full(50, 0.3), np.linspace(0.0, 1e-3, 50)])) == [0]
