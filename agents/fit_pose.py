"""``rdmp-gym fit --demo`` on a pose recording (a CSV with ``qw, qx, qy, qz`` beside the position): one DMP for
position and orientation, its report in mm and degrees."""

from __future__ import annotations

import json
from pathlib import Path
from types import ModuleType

from rdmp_gym import save_dmp
from rdmp_gym.dmp.pose import PoseDemonstration
from rdmp_gym.recordings.pose_fit import fit_pose_recording, pose_report
from rdmp_gym.recordings.recording_fit import constant_columns

__all__ = ["constant_note", "fit_pose_command"]


def fit_pose_command(pose: PoseDemonstration, hints: dict, out: Path, plots: ModuleType | None) -> None:
    """Fit ``pose`` with the fit's ``hints`` (keywords of :func:`~rdmp_gym.recordings.recording_fit.fit_recording`);
    write ``dmp.json``, ``report.json`` (and ``fit.png``: the position) into ``out``."""
    result = fit_pose_recording(pose, **hints)
    out.mkdir(parents=True, exist_ok=True)
    save_dmp(result.dmp, out / "dmp.json")
    seg, report = result.recording.segmentation, pose_report(pose, result)
    rest = "no final rest" if seg.rest_time is None else f"at rest from {seg.rest_time:.2f} s"
    print(f"{pose.demo.name}: period {seg.period:.3f} s, rhythm {seg.rhythm_start:.2f}-{seg.rhythm_end:.2f} s, "
          f"{rest}")
    print(f"position: cycle error {1000 * report['cycle_error']:.2f} mm vs cycle-to-cycle variation "
          f"{1000 * report['cycle_variation']:.2f} mm (x{report['error_ratio']:.2f}); peak acceleration "
          f"x{report['acceleration_ratio']:.2f} the smoothed recording's")
    constant = constant_columns(pose.position.Y)
    if constant:
        print(constant_note(constant))
    if report["orientation_constant"]:
        held = ", ".join(f"{value:.4f}" for value in pose.reference)
        print(f"orientation: constant (qw, qx, qy, qz = {held}), held by the DMP's anchor; reproduced within "
              f"{report['orientation_rmse']:.2g} deg over the rhythm")
    else:
        print(f"orientation: cycle error {report['orientation_error']:.2f} deg vs cycle-to-cycle variation "
              f"{report['orientation_variation']:.2f} deg (x{report['orientation_error_ratio']:.2f}); peak angular "
              f"acceleration {report['peak_angular_acceleration']:.0f} deg/s^2 vs "
              f"{report['recording_peak_angular_acceleration']:.0f} (x{report['angular_acceleration_ratio']:.2f})")
    (out / "report.json").write_text(json.dumps({"period": seg.period, "rhythm_start": seg.rhythm_start,
                                                 "rhythm_end": seg.rhythm_end, "rest_time": seg.rest_time,
                                                 "stop_at": result.recording.stop_at, **report,
                                                 "constant_columns": constant}, indent=2) + "\n")
    print(f"wrote {out / 'dmp.json'} and {out / 'report.json'}")
    if plots is not None:
        plots.plot_recording_fit(pose.demo.t - pose.demo.t[0], pose.position.Y,
                                 lambda t: result.reproduce(t).position, out / "fit.png",
                                 title=f"{pose.demo.name}: recording vs DMP (position)")
        print(f"wrote {out / 'fit.png'}")


def constant_note(columns: list[int]) -> str:
    """The line that names the position's constant dimensions (``constant_columns`` in ``report.json``)."""
    return (f"constant: dimension(s) {', '.join(map(str, columns))} of the position (from 0, constant_columns in "
            "report.json) never change in the recording; the DMP's anchor holds them")
