"""One DMP for several sessions: their mean rhythm at a common period, each session's anchor; the CLI's
``--sessions joint``."""

import json

import numpy as np
import pytest
from rdmp_gym.agents.cli import main as cli_main

from rdmp_gym.dmp.serialization import load_dmp
from rdmp_gym.recordings.session_fit import fit_joint, joint_report
from rdmp_gym.signals.demonstrations import to_demonstration
from rdmp_gym.synthetic.sessions import multi_session_recording


@pytest.fixture(scope="module")
def alike(tmp_path_factory, fit_command_demonstration):
    """Three kitchen sessions at the same mean period (0.9 s), each at its own working place, 12 periods of rhythm
    each (the kind's 20 cost 1.4x the session search for nothing these tests read; docs/fitting.md's joint-fit
    snippet runs the 20): the recording, its CSV and the demonstration that ``rdmp-gym fit --demo`` reads from it."""
    recording = multi_session_recording(3, "kitchen", rng=np.random.default_rng(1), periods=[0.9, 0.9, 0.9],
                                        n_periods=12)
    path = tmp_path_factory.mktemp("alike") / "alike.csv"
    recording.recording.to_csv(path)
    return recording, fit_command_demonstration(path), path


@pytest.fixture(scope="module")
def joint(alike, sharing_session_search):
    """The joint fit of the CLI's samples, searched once for it and for the CLI test (the shared session search)."""
    with sharing_session_search():
        return fit_joint(alike[1])


def test_each_session_is_reproduced_within_its_variation(alike, joint) -> None:
    rows = joint_report(alike[1], joint)
    assert len(rows) == len(alike[0].sessions) == 3
    for row, truth in zip(rows, alike[0].sessions, strict=True):
        assert row["error_ratio"] < 1.5
        assert row["period"] == pytest.approx(truth.period, rel=0.05)
        assert row["tempo"] == pytest.approx(joint.relative.period / row["period"])


def test_each_session_keeps_its_anchor(alike, joint) -> None:
    demo = alike[1]
    t = demo.t - demo.t[0]
    assert np.min(np.linalg.norm(joint.anchors[1:] - joint.anchors[:-1], axis=1)) > 0.1    # apart by the moves
    for k, session in enumerate(joint.sessions):
        seg = session.segmentation
        rhythm = (t >= session.start + seg.rhythm_start) & (t <= session.start + seg.rhythm_end)
        assert np.linalg.norm(joint.anchors[k] - demo.Y[rhythm].mean(axis=0)) < 0.01
        part = session.part(demo)
        inner = (part.t - part.t[0] >= seg.rhythm_start) & (part.t - part.t[0] <= seg.rhythm_end)
        reproduced = joint.reproduce(k, part.t - part.t[0])[inner]
        assert np.linalg.norm(reproduced.mean(axis=0) - demo.Y[rhythm].mean(axis=0)) < 0.01


def test_sessions_of_different_tempo_are_refused(alike, joint) -> None:
    recording = multi_session_recording(2, "kitchen", rng=np.random.default_rng(1), periods=[0.7, 1.1], n_periods=8)
    demo = to_demonstration(recording.recording.t, recording.recording.Y)
    with pytest.raises(ValueError, match=r"periods \(0\.[67]\d*, 1\.[01]\d* s\) differ by more than 15%"):
        fit_joint(demo)


def test_bad_input_names_the_argument(alike, joint) -> None:
    with pytest.raises(ValueError, match="period"):
        fit_joint(alike[1], list(joint.sessions), period=0.9)
    with pytest.raises(ValueError, match="ending"):
        fit_joint(alike[1], list(joint.sessions), ending=True)
    with pytest.raises(ValueError, match="k: expected a session index"):
        joint.at_session(3)


def test_cli_writes_one_dmp_with_each_anchor(alike, joint, tmp_path, shared_session_search) -> None:
    path = alike[2]
    out = tmp_path / "fit"
    assert cli_main(["fit", "--demo", str(path), "--sessions", "joint", "--out", str(out)]) == 0
    report = json.loads((out / "report.json").read_text())
    assert not (out / "dmp-1.json").exists()
    dmp = load_dmp(out / "dmp.json")
    assert len(report["sessions"]) == 3 and dmp.n_transients == 3
    for k, row in enumerate(report["sessions"]):
        t = np.arange(0.0, 6.0, 0.01)
        started = dmp.rollout(t, transient=row["transient"], anchor=np.array(row["anchor"]), y0=np.array(row["y0"]),
                              tempo=row["tempo"])
        # the same fit of the same samples (but for the report's rounding): session k from its entry, not the first
        # session moved
        np.testing.assert_allclose(started, joint.reproduce(k, t + joint.entries[k]), atol=5e-4)
        assert np.linalg.norm(started[-300:].mean(axis=0) - joint.anchors[k]) < 0.01
    hinted = ["fit", "--demo", str(path), "--sessions", "joint", "--period", "0.9", "--out", str(tmp_path / "no")]
    assert cli_main(hinted) == 2        # a hint of one rhythm with the joint fit: refused
    assert not (tmp_path / "no").exists()
