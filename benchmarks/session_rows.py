"""The session rows of ``bench_recordings.py --sessions``: the sessions found in a recording, each one's onset and
stop against the truth or the hand labels, its period, cycle error against its cycle-to-cycle variation, peak
acceleration ratio, the joint fit's error ratio per session (or why it is refused), and whether ``rdmp-gym fit
--demo`` succeeds on the whole file."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
from rdmp_gym.agents.cli import main as cli_main

from rdmp_gym.recordings.session_fit import fit_joint, fit_sessions, joint_report


def session_row(name: str, demo, labels: list[tuple[float, float]] | None, csv_path: Path) -> dict:
    """One recording's row: ``sessions`` (one dict per session found) and, per labelled session, the offsets
    (s, detected minus labelled) of the first onset and last stop of the sessions found within it."""
    row: dict = {"recording": name, "duration": round(demo.duration, 2)}
    try:
        fits = fit_sessions(demo)
    except ValueError as error:
        fits, row["error"] = [], str(error)
    row["sessions"] = [_session(item) for item in fits]
    row["joint"] = _joint(demo, [item.session for item in fits]) if len(fits) > 1 else None
    if labels:
        row["labels"] = _against(labels, row["sessions"])
    with tempfile.TemporaryDirectory() as folder:
        row["cli"] = cli_main(["fit", "--demo", str(csv_path), "--out", folder]) == 0
    return row


def _session(item) -> dict:
    session = item.session
    out = {"start": session.start, "stop": session.stop, "onset": session.rhythm_onset,
           "rhythm_stop": session.rhythm_stop}
    try:
        report = item.report()
    except ValueError as error:             # refused, or too few whole cycles to measure
        return {**out, "error": str(error)}
    return {**out, "period": item.recording.segmentation.period,
            **{key: report[key] for key in ("cycle_error", "cycle_variation", "error_ratio", "start_error",
                                            "rest_error", "acceleration_ratio")}}


def _joint(demo, sessions) -> dict:
    """The joint fit's error ratio per session, or why it is refused."""
    try:
        return {"error_ratio": [row["error_ratio"] for row in joint_report(demo, fit_joint(demo, sessions))]}
    except ValueError as error:
        return {"error": str(error)}


def _against(labels: list[tuple[float, float]], sessions: list[dict]) -> list[dict]:
    """Each session found against the labelled sessions it overlaps (the first one's start, the last one's end),
    then the labelled sessions that no session found overlaps."""
    rows, matched = [], set()
    for s in sessions:
        inside = [k for k, (start, end) in enumerate(labels) if s["onset"] < end and s["rhythm_stop"] > start]
        if inside:
            matched.update(inside)
            rows.append({"label": [labels[inside[0]][0], labels[inside[-1]][1]], "labels": len(inside), "found": 1,
                         "onset_offset": s["onset"] - labels[inside[0]][0],
                         "stop_offset": s["rhythm_stop"] - labels[inside[-1]][1]})
    return rows + [{"label": list(label), "labels": 1, "found": 0} for k, label in enumerate(labels)
                   if k not in matched]


def print_session_row(row: dict) -> None:
    """The row as a few lines."""
    found = len(row["sessions"])
    labelled = f", {len(row['labels'])} labelled" if "labels" in row else ""
    print(f"{row['recording']:>28}: {found} session(s){labelled}; CLI {'ok' if row['cli'] else 'failed'}"
          + (f" ({row['error']})" if "error" in row else ""))
    for k, s in enumerate(row["sessions"], start=1):
        head = f"{'':>30}{k}: rhythm {s['onset']:6.2f}-{s['rhythm_stop']:6.2f} s"
        if "error" in s:
            print(f"{head}, refused: {s['error']}")
            continue
        rest = "-" if s["rest_error"] is None else f"{1000 * s['rest_error']:.1f}"
        print(f"{head}, period {s['period']:.3f} s, cycle error {1000 * s['cycle_error']:.2f} / "
              f"{1000 * s['cycle_variation']:.2f} mm = {s['error_ratio']:.2f}, start/rest "
              f"{1000 * s['start_error']:.1f}/{rest} mm, accel ratio {s['acceleration_ratio']:.2f}")
    for label in row.get("labels", []):
        offsets = (f"onset {label['onset_offset']:+.2f} s, stop {label['stop_offset']:+.2f} s"
                   if label["found"] else "not found")
        print(f"{'':>30}{label['labels']} label(s) {label['label'][0]:.2f}-{label['label'][1]:.2f}: {offsets}")
    if row.get("joint"):
        joint = row["joint"]
        print(f"{'':>30}joint: " + (f"refused: {joint['error']}" if "error" in joint else
                                     "error ratios " + ", ".join(f"{v:.2f}" for v in joint["error_ratio"])))


def session_summary(title: str, rows: list[dict]) -> None:
    """Sessions found against labelled, the offsets of onsets and stops, the worst ratios."""
    labels = [label for row in rows for label in row.get("labels", [])]
    fitted = [s for row in rows for s in row["sessions"] if "error" not in s]
    print(f"{title}: {sum(len(row['sessions']) for row in rows)} sessions found in {len(rows)} recordings, "
          f"{len(fitted)} fitted; CLI ok on {sum(row['cli'] for row in rows)}")
    matched = [label for label in labels if label["found"]]
    if labels:
        print(f"  labelled sessions found: {sum(label['labels'] for label in matched)} of "
              f"{sum(label['labels'] for label in labels)} (in {len(matched)} sessions found)")
    for key in ("onset_offset", "stop_offset"):
        values = np.abs([label[key] for label in matched])
        if values.size:
            print(f"  |{key}|: {np.sum(values <= 0.5)} of {values.size} <= 0.5 s, max {values.max():.2f} s, "
                  f"median {np.median(values):.2f} s")
    for key in ("error_ratio", "acceleration_ratio"):
        values = [s[key] for s in fitted]
        if values:
            print(f"  {key}: {sum(v <= 1.5 for v in values)} of {len(values)} <= 1.5 (worst {max(values):.3g})")
