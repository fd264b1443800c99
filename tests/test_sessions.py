"""Several sessions in one recording: the split, the onset and stop of each rhythm, one fit per session, the CLI."""

import itertools
import json

import numpy as np
import pytest
from rdmp_gym.agents.cli import main as cli_main

from rdmp_gym import load_dmp
from rdmp_gym.dmp import quaternion
from rdmp_gym.recordings.pose_io import write_pose_csv
from rdmp_gym.recordings.recording_fit import recording_report
from rdmp_gym.recordings.session_fit import SessionFit, fit_sessions
from rdmp_gym.signals.demonstrations import Demonstration, to_demonstration
from rdmp_gym.signals.segmentation import segment_rhythm
from rdmp_gym.signals.segmentation.sessions import find_sessions
from rdmp_gym.synthetic.demonstrations import realistic_recording
from rdmp_gym.synthetic.sessions import multi_session_pose_recording, multi_session_recording


@pytest.fixture(scope="module")
def three(tmp_path_factory, fit_command_demonstration):
    """A recording of three wiping sessions of periods 1.45, 1.7 and 1.95 s, its CSV and the demonstration that
    ``rdmp-gym fit --demo`` reads from it."""
    recording = multi_session_recording(3, "wiping", rng=np.random.default_rng(1))
    path = tmp_path_factory.mktemp("three") / "three.csv"
    recording.recording.to_csv(path)
    return recording, fit_command_demonstration(path), path


@pytest.fixture(scope="module")
def fits(three, sharing_session_search):
    """The sessions' fits, searched once for them and for the CLI test (the shared session search)."""
    with sharing_session_search():
        return fit_sessions(three[1])


def test_generator_is_seeded_and_continuous(three) -> None:
    again = multi_session_recording(3, "wiping", rng=np.random.default_rng(1))
    np.testing.assert_array_equal(again.recording.Y, three[0].recording.Y)
    assert np.all(np.diff(three[0].recording.t) > 0.0)
    jumps = np.linalg.norm(np.diff(three[0].clean, axis=0), axis=1)
    assert jumps.max() < 0.01                       # each session starts where the previous one rested
    truths = three[0].sessions
    assert all(a.rest_time < b.onset for a, b in itertools.pairwise(truths))


def test_each_session_is_found_with_its_onset_and_stop(fits, three) -> None:
    truths = three[0].sessions
    assert len(fits) == len(truths)
    for item, truth in zip(fits, truths, strict=True):
        session = item.session
        assert session.start <= truth.onset and truth.stop <= session.stop      # the cuts hold the whole session
        # test_onset.py's bounds for generated sessions (its seed-0 recordings are in the slow set)
        assert abs(session.rhythm_onset - truth.onset) < 0.8      # the growth starts while the hand approaches
        assert abs(session.rhythm_stop - truth.stop) < 0.5
        assert item.fit.segmentation.period == pytest.approx(truth.period, rel=0.05)
    cuts = [(item.session.start, item.session.stop) for item in fits]
    assert cuts[0][0] == 0.0 and cuts[-1][1] == pytest.approx(three[1].t[-1] - three[1].t[0])
    assert all(a[1] == b[0] for a, b in itertools.pairwise(cuts))       # back to back


def test_each_session_is_fitted_within_the_targets(fits) -> None:
    for item in fits:
        report = recording_report(item.demo, item.fit)
        assert report["error_ratio"] < 1.5
        assert report["acceleration_ratio"] < 1.5
        assert report["rest_error"] is not None and report["rest_error"] < 0.01
        assert item.report() == report and item.recording is item.fit


def test_a_refused_session_reports_why(fits) -> None:
    refused = SessionFit(fits[0].session, fits[0].demo, None, "demo: the rhythm spans only 1.4 periods")
    assert refused.recording is None
    with pytest.raises(ValueError, match=r"spans only 1\.4 periods"):
        refused.report()


def test_one_session_is_the_whole_recording() -> None:
    recording = realistic_recording("wiping", rng=np.random.default_rng(2))
    demo = to_demonstration(recording.t, recording.Y)
    sessions = find_sessions(demo)
    assert len(sessions) == 1
    assert sessions[0].start == 0.0 and sessions[0].stop == pytest.approx(demo.t[-1] - demo.t[0])


@pytest.mark.parametrize("kind", ["wiping", "kitchen", "long"])
def test_onset_and_stop_surround_the_full_size_rhythm(kind: str) -> None:
    recording = realistic_recording(kind, rng=np.random.default_rng(1))
    seg = segment_rhythm(to_demonstration(recording.t, recording.Y))
    truth = recording.truth
    assert seg.rhythm_onset <= seg.rhythm_start < seg.rhythm_end <= seg.rhythm_stop
    assert seg.rhythm_onset < truth.rhythm_start                # earlier than the full-size rhythm
    assert abs(seg.rhythm_stop - truth.rhythm_end) < 1.0


def test_bad_input_names_the_argument(three) -> None:
    with pytest.raises(ValueError, match="period"):
        fit_sessions(three[1], period=1.7)
    with pytest.raises(ValueError, match="n_sessions"):
        multi_session_recording(1, rng=np.random.default_rng(0))
    with pytest.raises(ValueError, match="periods"):
        multi_session_recording(2, rng=np.random.default_rng(0), periods=[1.5])
    noise = np.random.default_rng(0).normal(0.0, 1e-3, (1500, 3))
    with pytest.raises(ValueError, match="no rhythm"):
        find_sessions(Demonstration(np.arange(1500) * 0.01, noise))


def test_cli_writes_one_dmp_per_session(three, fits, tmp_path, shared_session_search) -> None:
    assert cli_main(["fit", "--demo", str(three[2]), "--out", str(tmp_path / "fit")]) == 0
    report = json.loads((tmp_path / "fit" / "report.json").read_text())
    assert [row["dmp"] for row in report["sessions"]] == ["dmp-1.json", "dmp-2.json", "dmp-3.json"]
    assert all((tmp_path / "fit" / f"dmp-{k}.json").exists() for k in (1, 2, 3))
    assert not (tmp_path / "fit" / "dmp.json").exists()



def _paused(lift: float, hold: float) -> tuple[Demonstration, float]:
    """A kitchen recording (period 0.9 s) whose hand stops mid-stroke in the middle of its rhythm for ``hold`` s,
    lifting by ``lift`` m (a smooth bump in z), and where the pause starts (s)."""
    recording = realistic_recording("kitchen", rng=np.random.default_rng(0))
    truth = recording.truth
    k = int(np.searchsorted(recording.t, 0.5 * (truth.rhythm_start + truth.rhythm_end)))
    dt = float(np.median(np.diff(recording.t)))
    n = round(hold / dt)
    bump = np.sin(np.linspace(0.0, np.pi, n)) ** 2
    still = recording.Y[k] + np.outer(bump, [0.0, 0.0, lift]) + np.random.default_rng(1).normal(0.0, 2e-4, (n, 3))
    t = np.concatenate([recording.t[:k], recording.t[k] + dt * np.arange(n), recording.t[k:] + n * dt])
    return to_demonstration(t, np.concatenate([recording.Y[:k], still, recording.Y[k:]])), recording.t[k]


def test_a_pause_at_the_working_place_is_one_session() -> None:
    demo, pause = _paused(0.03, hold=1.5)   # 1.7 periods' pause, 3 cm off the surface (0.65 of the rhythm's size)
    sessions = find_sessions(demo)
    assert len(sessions) == 1
    assert sessions[0].rhythm_onset < pause - 5.0 and sessions[0].rhythm_stop > pause + 5.0


def test_a_departure_separates_sessions() -> None:
    demo, pause = _paused(0.2, hold=2.0)        # the hand leaves: 20 cm up and back
    sessions = find_sessions(demo)
    assert len(sessions) == 2
    assert sessions[0].rhythm_stop <= pause + 0.5 and sessions[1].rhythm_onset >= pause + 1.5


def _wobbling_approach(share: float) -> tuple[Demonstration, float]:
    """A hand that comes down onto the table (z = 0) in 5 s wobbling along x at period 1.8 s with ``share`` of the
    rhythm's amplitude, strokes figures of eight of 0.1 m at period 0.93 s from 6 s for 20 periods and lifts off;
    and where the strokes start (s)."""
    dt, period, amplitude, down, onset = 0.01, 0.93, 0.1, 5.0, 6.0
    end = onset + 20 * period
    t = np.arange(0.0, end + 3.0, dt)
    wobble = share * amplitude * np.sin(2 * np.pi * t / 1.8) * np.clip((down - t) / 0.5, 0.0, 1.0)
    stroking = (t >= onset) & (t < end)
    phase = 2 * np.pi * (t - onset) / period
    lift = np.clip((t - end - 1.0) / 1.0, 0.0, 1.0)
    x = np.where(stroking, amplitude * np.sin(phase), 0.0) + wobble
    y = np.where(stroking, 0.3 * amplitude * np.sin(2 * phase), 0.0) + 0.1 * lift
    z = 0.1 * (1.0 - np.clip(t / down, 0.0, 1.0)) + 0.2 * lift ** 2
    Y = np.column_stack([x, y, z]) + 0.0005 * np.random.default_rng(0).standard_normal((t.size, 3))
    return to_demonstration(t, Y), onset


@pytest.mark.parametrize("share", [pytest.param(0.4, marks=pytest.mark.slow), 0.5])   # 0.4: in the slow set
def test_a_small_slow_wobble_of_the_approach_is_no_session(share: float) -> None:
    demo, onset = _wobbling_approach(share)     # the wobble repeats, at about 0.35-0.45 of the rhythm's size
    sessions = find_sessions(demo)
    assert len(sessions) == 1
    assert abs(sessions[0].rhythm_onset - onset) < 0.2


@pytest.fixture(scope="module")
def pose_sessions():
    """Two wiping sessions with the tool's orientation (periods 1.45 and 1.7 s)."""
    return multi_session_pose_recording(2, "wiping", rng=np.random.default_rng(2))


def test_pose_generator_joins_the_orientations_continuously(pose_sessions) -> None:
    clean = pose_sessions.clean_orientation
    steps = np.degrees(quaternion.angle_between(clean[:-1], clean[1:]))
    assert np.allclose(np.linalg.norm(clean, axis=1), 1.0)
    assert steps.max() < 2.0                    # deg per 10 ms sample: no jump where the sessions meet
    assert np.allclose(np.abs(np.sum(pose_sessions.Q * clean, axis=1)), 1.0, atol=1e-4)     # q or -q, noisy


def test_cli_fits_each_session_of_a_pose_recording(pose_sessions, tmp_path, shared_session_search) -> None:
    path = tmp_path / "pose_sessions.csv"
    pose_sessions.to_csv(path)
    assert cli_main(["fit", "--demo", str(path), "--out", str(tmp_path / "fit")]) == 0
    rows = json.loads((tmp_path / "fit" / "report.json").read_text())["sessions"]
    assert len(rows) == len(pose_sessions.sessions) == 2
    for row, truth in zip(rows, pose_sessions.sessions, strict=True):
        assert row["start"] <= truth.onset and truth.rest_time - 0.5 <= row["stop"]
        assert abs(row["period"] - truth.period) < 0.05 * truth.period
        assert row["error_ratio"] <= 1.5 and row["acceleration_ratio"] <= 1.5
        assert row["orientation_error_ratio"] <= 1.5 and row["angular_acceleration_ratio"] <= 1.5
        assert load_dmp(tmp_path / "fit" / row["dmp"]).rollout(np.arange(0.0, 2.0, 0.01)).orientation.shape \
            == (200, 4)
    joint = ["fit", "--demo", str(path), "--sessions", "joint", "--out", str(tmp_path / "joint")]
    assert cli_main(joint) == 2 and not (tmp_path / "joint").exists()


def test_cli_fits_each_session_of_a_pose_recording_held_level(pose_sessions, tmp_path, capsys,
                                                            shared_session_search) -> None:
    """The same quaternion on every row (a tool held level): every session fits, its orientation named constant.
    The position is the previous test's: the session search (by position) is shared with it."""
    path = tmp_path / "held.csv"
    write_pose_csv(path, pose_sessions.t, pose_sessions.Y, np.tile([0.0, 1.0, 0.0, 0.0], (pose_sessions.t.size, 1)))
    assert cli_main(["fit", "--demo", str(path), "--out", str(tmp_path / "fit")]) == 0
    rows = json.loads((tmp_path / "fit" / "report.json").read_text())["sessions"]
    assert len(rows) == 2 and all("error" not in row for row in rows)
    for row in rows:
        assert row["orientation_constant"] and row["orientation_variation"] == 0.0 and row["error_ratio"] <= 1.5
        held = load_dmp(tmp_path / "fit" / row["dmp"]).rollout(np.arange(0.0, 2.0, 0.01)).orientation
        assert np.degrees(quaternion.angle_between(held, [0.0, 1.0, 0.0, 0.0])).max() < 1e-9
    assert "constant" in capsys.readouterr().out
