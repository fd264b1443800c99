"""Pose DMPs: orientation fitted beside the position on one canonical system, mapped back to unit quaternions."""

import json

import numpy as np
import pytest
from rdmp_gym.agents.cli import main as cli_main

from rdmp_gym import load_dmp, save_dmp
from rdmp_gym.dmp import quaternion
from rdmp_gym.dmp.pose import PoseDemonstration, PoseDMP
from rdmp_gym.dmp.rhythmic import RhythmicDMP
from rdmp_gym.recordings.pose_fit import fit_pose_recording, pose_report
from rdmp_gym.recordings.recording_fit import fit_recording
from rdmp_gym.signals.demonstrations import to_demonstration
from rdmp_gym.synthetic.pose import realistic_pose_recording


def _fitted(**keywords):
    recording = realistic_pose_recording("wiping", rng=np.random.default_rng(0), **keywords)
    pose = PoseDemonstration.from_samples(recording.t, recording.Y, recording.Q, name="wiping")
    return recording, pose, fit_pose_recording(pose)


@pytest.fixture(scope="module")
def wiping():
    return _fitted()


def test_the_pose_fit_meets_the_targets_and_its_position_is_the_position_fit(wiping):
    recording, pose, result = wiping
    report = pose_report(pose, result)
    assert report["error_ratio"] < 1.5 and report["orientation_error_ratio"] < 1.5
    assert report["acceleration_ratio"] < 1.5 and report["angular_acceleration_ratio"] < 1.5
    assert report["orientation_rmse"] < 3.0 and report["orientation_start_error"] < 1.0
    alone = fit_recording(to_demonstration(recording.t, recording.Y))
    t = pose.demo.t
    assert np.allclose(result.reproduce(t).position, alone.reproduce(t), atol=1e-9)


def test_the_reproduced_orientation_is_unit_and_never_flips_sign(wiping):
    _, pose, result = wiping
    q = result.reproduce(np.arange(0.0, pose.demo.duration, 1e-3)).orientation
    assert np.max(np.abs(np.linalg.norm(q, axis=1) - 1.0)) < 1e-12
    assert np.min(np.sum(q[1:] * q[:-1], axis=1)) > 0.99


def test_q_and_minus_q_in_the_recording_or_the_start_are_one_orientation(wiping):
    recording, pose, result = wiping
    flipped = recording.Q * np.where(np.arange(recording.t.size) % 2 == 0, -1.0, 1.0)[:, None]
    other = PoseDemonstration.from_samples(recording.t, recording.Y, flipped)
    assert np.allclose(other.demo.Y, pose.demo.Y, atol=1e-12)
    t = np.arange(0.0, 5.0, 0.01)
    q0 = pose.orientations[0]
    plus, minus = (result.dmp.rollout(t, orientation=sign * q0) for sign in (1.0, -1.0))
    assert np.allclose(plus.orientation, minus.orientation, atol=1e-12)
    assert quaternion.angle_between(plus.orientation[0], q0) < 1e-9


def test_a_slow_half_turn_during_the_approach_is_reproduced():
    recording, pose, result = _fitted(turn=180.0)
    report = pose_report(pose, result)
    assert report["orientation_error_ratio"] < 1.5 and report["angular_acceleration_ratio"] < 1.5
    reproduced = result.reproduce(pose.demo.t).orientation
    assert np.degrees(quaternion.angle_between(reproduced[0], recording.clean_orientation[0])) < 2.0
    turned = np.degrees(quaternion.angle_between(reproduced[0], reproduced[int(result.recording.segmentation
                                                                                    .rhythm_start / pose.demo.dt)]))
    assert 150.0 < turned <= 180.0
    assert np.max(np.degrees(quaternion.angle_between(reproduced, pose.orientations))) < 8.0


def test_an_orientation_that_barely_moves_is_held():
    recording = realistic_pose_recording("wiping", rng=np.random.default_rng(3))
    still = quaternion.exp_map(np.array([0.3, -0.2, 1.0]))
    noise = quaternion.exp_map(np.random.default_rng(4).normal(0.0, 1e-4, (recording.t.size, 3)))
    pose = PoseDemonstration.from_samples(recording.t, recording.Y, quaternion.multiply(still, noise))
    result = fit_pose_recording(pose)
    reproduced = result.reproduce(np.arange(0.0, pose.demo.duration, 0.005)).orientation
    assert np.max(np.degrees(quaternion.angle_between(reproduced, still))) < 0.05
    report = pose_report(pose, result)
    assert all(np.isfinite(value) for value in report.values() if value is not None)


def test_batched_rollouts_and_the_stepper_give_the_rollout(wiping):
    _, _, result = wiping
    dmp = result.dmp
    t = np.arange(0.0, 6.0, 0.01)
    single = dmp.rollout(t)
    batch = dmp.rollout_batch(np.repeat(dmp.dmp.get_params()[None], 2, axis=0), t)
    assert batch.position.shape == (2, t.size, 3) and batch.orientation.shape == (2, t.size, 4)
    assert np.allclose(batch.orientation[1], single.orientation, atol=1e-9)
    stepper = dmp.start(0.01)
    steps = [stepper.pose] + [stepper.step() for _ in range(t.size - 1)]
    assert np.allclose([s.position for s in steps], single.position, atol=1e-9)
    assert np.allclose([s.orientation for s in steps], single.orientation, atol=1e-9)


def test_save_and_load_keep_the_orientation(wiping, tmp_path):
    *_, result = wiping
    path = tmp_path / "dmp.json"
    save_dmp(result.dmp, path)
    loaded = load_dmp(path)
    assert isinstance(loaded, PoseDMP)
    t = np.arange(0.0, 4.0, 0.01)
    assert np.array_equal(loaded.rollout(t).orientation, result.dmp.rollout(t).orientation)
    data = json.loads(path.read_text())
    data["orientation"]["reference"] = [0.0, 0.0, 0.0, 0.0]
    path.write_text(json.dumps(data))
    with pytest.raises(ValueError, match=r"dmp\.orientation\.reference: has norm 0"):
        load_dmp(path)
    save_dmp(result.dmp.position, path)              # a file without orientation: a plain DMP, as before
    assert isinstance(load_dmp(path), RhythmicDMP)


def test_the_command_fits_a_pose_csv_and_names_bad_columns(tmp_path, capsys, shared_session_search):
    recording = realistic_pose_recording("wiping", rng=np.random.default_rng(1))
    path = tmp_path / "rec.csv"
    recording.to_csv(path)
    assert cli_main(["fit", "--demo", str(path), "--out", str(tmp_path / "out")]) == 0
    report = json.loads((tmp_path / "out" / "report.json").read_text())
    assert report["orientation_error_ratio"] < 1.5 and report["error_ratio"] < 1.5
    assert isinstance(load_dmp(tmp_path / "out" / "dmp.json"), PoseDMP)
    rows = np.column_stack([recording.t, recording.Y, recording.Q])
    np.savetxt(path, rows[:, :7], delimiter=",", header="t,x,y,z,qw,qx,qy", comments="")
    assert cli_main(["fit", "--demo", str(path), "--out", str(tmp_path / "bad")]) == 2
    assert "lacks ['qz']" in capsys.readouterr().err
    rows[10, 4:] = 0.0
    np.savetxt(path, rows, delimiter=",", header="t,x,y,z,qw,qx,qy,qz", comments="")
    assert cli_main(["fit", "--demo", str(path), "--out", str(tmp_path / "bad")]) == 2
    assert "orientations: row 10 has norm 0" in capsys.readouterr().err


@pytest.mark.parametrize("held", [[1.0, 0.0, 0.0, 0.0], [0.6, -0.2, 0.7, 0.3]], ids=["identity", "tilted"])
def test_a_constant_orientation_fits_as_the_anchor_and_the_report_says_so(wiping, held):
    """A controller's log of a tool held level: the same quaternion on every row (with either sign)."""
    recording, varying, varying_fit = wiping
    q = np.asarray(held) / np.linalg.norm(held)
    signs = np.where(np.random.default_rng(3).random(recording.t.size) < 0.5, -1.0, 1.0)[:, None]
    pose = PoseDemonstration.from_samples(recording.t, recording.Y, q * signs, name="held")
    result = fit_pose_recording(pose)
    report = pose_report(pose, result)
    assert report["orientation_constant"] and not pose_report(varying, varying_fit)["orientation_constant"]
    assert report["orientation_variation"] == 0.0 and report["orientation_error"] < 1e-9
    t = np.arange(0.0, pose.demo.t[-1] - pose.demo.t[0], 0.01)
    assert np.degrees(quaternion.angle_between(result.reproduce(t).orientation, q)).max() < 1e-9
    assert np.abs(result.dmp.tangent.weights).max() < 1e-12        # the anchor alone holds it
    varied = pose_report(varying, varying_fit)        # the orientation does not touch the position's fit
    position = [key for key in varied if "orientation" not in key and "angular" not in key]
    assert "cycle_variation" in position and all(report[key] == varied[key] for key in position)


def test_the_command_fits_a_pose_csv_with_a_constant_orientation(tmp_path, capsys, shared_session_search):
    """The previous test's recording with the tool held level: its positions (exact in both CSVs) share that test's
    session search."""
    recording = realistic_pose_recording("wiping", rng=np.random.default_rng(1))
    path = tmp_path / "held.csv"
    np.savetxt(path, np.column_stack([recording.t, recording.Y, np.tile([1.0, 0.0, 0.0, 0.0], (recording.t.size, 1))]),
               delimiter=",", header="t,x,y,z,qw,qx,qy,qz", comments="")
    assert cli_main(["fit", "--demo", str(path), "--out", str(tmp_path / "out")]) == 0
    report = json.loads((tmp_path / "out" / "report.json").read_text())
    assert report["orientation_constant"] and report["error_ratio"] < 1.5
    assert "orientation: constant" in capsys.readouterr().out
    assert isinstance(load_dmp(tmp_path / "out" / "dmp.json"), PoseDMP)
