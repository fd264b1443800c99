"""Whole-recording fits: segmentation against the truth, cycle error against the recording's own cycle-to-cycle
variation, start and rest error, peak acceleration ratio, and whether ``rdmp-gym fit --demo`` succeeds.

By default on the realistic recordings of :mod:`rdmp_gym.synthetic.demonstrations` (3 kinds x ``--seeds`` seeds),
against the generator's truth; with ``--data PATH`` also on the user's own recordings (CSV files ``t,x,y,z`` under PATH,
or the 12-column pose files ``*.txt`` of homogeneous transforms that some datasets ship, read at ``--data-rate`` Hz),
against hand labels where a file ``NAME.labels.json`` beside ``NAME.csv`` gives ``{"rhythm_start": s,
"rhythm_end": s}`` (s from the first time stamp). Third-party data is read, never copied: the user's rows go to
``runs/benchmarks/recordings_user.json`` (untracked), the generated ones to ``recordings.json``. Targets: error
ratio <= 1.5, start and rest error <= 1 cm, acceleration ratio <= 1.5.

With ``--orientation`` also the pose (position and orientation): realistic pose recordings
(:func:`rdmp_gym.synthetic.pose.realistic_pose_recording`) and the user's files with ``qw, qx, qy, qz`` columns or
12-column pose files, with the orientation's cycle error against its cycle-to-cycle variation (degrees) and its
peak angular acceleration ratio (``recordings_pose.json``).

With ``--sessions`` also the recordings with several sessions: generated ones
(:func:`rdmp_gym.synthetic.sessions.multi_session_recording`, 3 sessions of each kind) against their truth, and the
user's files against labels ``{"sessions": [{"rhythm_start": s, "rhythm_end": s}, ...]}`` (or the single-rhythm
form): sessions found, each one's onset and stop against the labels, period, error and acceleration ratios, the
joint fit's error ratios (:func:`rdmp_gym.recordings.session_fit.fit_joint`; also on 3 sessions of one period of each
kind), and whether the CLI succeeds (``recordings_sessions.json``, the ``--data`` rows beside the generated ones: the
figures of your files, not the files).

    python benchmarks/bench_recordings.py [--seeds 3] [--data PATH --data-rate 100] [--orientation] [--sessions]
                                          [--save]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np
from output import add_save_argument, results_dir
from pose_rows import pose_row, print_pose_row, read_orientation, summary
from rdmp_gym.agents.cli import main as cli_main
from session_rows import print_session_row, session_row, session_summary

from rdmp_gym.recordings.recording_fit import fit_recording, recording_report
from rdmp_gym.signals.demonstrations import to_demonstration
from rdmp_gym.signals.filters import smooth_derivatives
from rdmp_gym.synthetic.demonstrations import RECORDING_KINDS, realistic_recording
from rdmp_gym.synthetic.pose import realistic_pose_recording
from rdmp_gym.synthetic.sessions import multi_session_pose_recording, multi_session_recording


def _row(name: str, demo, truth: dict | None, csv_path: Path, clean=None) -> dict:
    """One table row; ``truth``: known or labelled ``period``, ``start``, ``end``, ``rest`` (s, any of them);
    ``clean``: the noise-free recording (a Demonstration), where known."""
    row = {"recording": name, "duration": round(demo.duration, 2)}
    try:
        result = fit_recording(demo)
        seg = result.segmentation
        row.update(period=seg.period, start=seg.rhythm_start, end=seg.rhythm_end, rest=seg.rest_time,
                   **recording_report(demo, result))
    except ValueError as error:
        row["error"] = str(error)
    for key, value in (truth or {}).items():
        row[f"true_{key}"] = value
        if row.get(key) is not None and value is not None:      # detected minus true (s)
            row[f"{key}_offset"] = row[key] - value
    if clean is not None and "peak_acceleration" in row:    # the noise-free signal's peak, beside the recording's
        peak = float(np.max(np.linalg.norm(smooth_derivatives(clean.Y, clean.dt, 0.15)[2], axis=1)))
        row.update(clean_peak_acceleration=peak, clean_acceleration_ratio=row["peak_acceleration"] / peak)
    with tempfile.TemporaryDirectory() as folder:
        row["cli"] = cli_main(["fit", "--demo", str(csv_path), "--out", folder]) == 0
    return row


def _pose_file(path: Path, rate: float):
    """A 12-column pose file (rows of a 3x4 transform, row-major) as (t, positions [L, 3])."""
    data = np.loadtxt(path)
    return np.arange(data.shape[0]) / rate, data[:, [3, 7, 11]]


def _user_recordings(folder: Path, rate: float):
    """``(path, t [L], Y [L, 3], labels or None)`` for every recording under ``folder``."""
    for path in sorted(folder.rglob("*")):
        if path.suffix.lower() == ".csv":
            data = np.genfromtxt(path, delimiter=",", names=True)
            names = data.dtype.names
            t, Y = np.asarray(data[names[0]]), np.column_stack([data[n] for n in names[1:4]])
        elif path.suffix.lower() == ".txt":
            t, Y = _pose_file(path, rate)
        else:
            continue
        labels = path.with_suffix(".labels.json")
        yield path, t, Y, (_labels(labels) if labels.exists() else None)


def _labels(path: Path) -> dict | None:
    """Hand labels ``{"start": s, "end": s}`` from a ``{"rhythm_start": s, "rhythm_end": s}`` file (``None`` for
    a file of several sessions)."""
    labels = json.loads(path.read_text())
    if "sessions" in labels:
        return None
    return {"start": float(labels["rhythm_start"]), "end": float(labels["rhythm_end"])}


def _session_labels(path: Path) -> list[tuple[float, float]] | None:
    """``[(start, end), ...]`` (s) of the labelled sessions in ``path`` (either form), ``None`` without a file."""
    if not path.exists():
        return None
    labels = json.loads(path.read_text())
    return [(float(s["rhythm_start"]), float(s["rhythm_end"])) for s in labels.get("sessions", [labels])]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", type=int, default=3, help="seeds per kind of generated recording")
    parser.add_argument("--data", type=Path, default=None, help="a folder of the user's recordings (opt-in)")
    parser.add_argument("--data-rate", type=float, default=100.0, help="sampling rate of pose files without time")
    parser.add_argument("--sessions", action="store_true",
                        help="also the recordings with several sessions (generated, and the --data files); writes "
                             "recordings_sessions.json")
    parser.add_argument("--orientation", action="store_true",
                        help="also fit position and orientation (realistic_pose_recording, and the --data files with "
                             "an orientation); writes recordings_pose.json")
    add_save_argument(parser)
    args = parser.parse_args(argv)
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for kind in RECORDING_KINDS:
            for seed in range(args.seeds):
                recording = realistic_recording(kind, rng=np.random.default_rng(seed))
                csv_path = Path(folder) / f"{kind}-{seed}.csv"
                recording.to_csv(csv_path)
                demo = to_demonstration(recording.t, recording.Y, name=f"{kind} {seed}")
                clean = to_demonstration(recording.t, recording.truth.clean, outliers=False)
                truth = recording.truth
                rows.append(_row(f"{kind} {seed}", demo, {"period": truth.period, "start": truth.rhythm_start,
                                                          "end": truth.rhythm_end, "rest": truth.rest_time},
                                 csv_path, clean))
                _print(rows[-1])
        _summary("generated", rows)
        user = []
        if args.data is not None:
            for path, t, Y, labels in _user_recordings(args.data, args.data_rate):
                csv_path = Path(folder) / f"{path.stem}.csv"
                np.savetxt(csv_path, np.column_stack([t, Y]), delimiter=",", header="t,x,y,z", comments="")
                name = str(path.relative_to(args.data))
                user.append(_row(name, to_demonstration(t, Y, name=path.stem), labels, csv_path))
                _print(user[-1])
            _summary("yours", user)
    if args.orientation:
        _pose_rows(args)
    if args.sessions:
        _session_rows(args)
    _write("recordings", rows, user, args.save)
    return 0


def _write(name: str, rows: list[dict], user: list[dict], save: bool) -> None:
    """The generated rows to ``<name>.json`` (committed with ``--save``), the user's to ``<name>_user.json``
    (never committed)."""
    out = results_dir(save) / f"{name}.json"
    out.write_text(json.dumps({"generated": rows}, indent=2, default=float) + "\n")
    print(f"wrote {out}")
    if user:
        out = results_dir(False) / f"{name}_user.json"
        out.write_text(json.dumps({"user": user}, indent=2, default=float) + "\n")
        print(f"wrote {out}")


def _pose_rows(args: argparse.Namespace) -> None:
    """The pose rows: generated recordings (the positions of the rows above, with an orientation; a slow half
    turn during the approach for every second seed; two sessions of each kind) and the user's files with an
    orientation."""
    rows, user = [], []
    for kind in RECORDING_KINDS:
        for seed in range(args.seeds):
            turn = 180.0 if seed % 2 else 0.0
            recording = realistic_pose_recording(kind, rng=np.random.default_rng(seed), turn=turn)
            truth = recording.truth
            rows.append(pose_row(f"{kind} {seed}" + (" turn" if turn else ""), recording.t, recording.Y,
                                 recording.Q, {"period": truth.period, "start": truth.rhythm_start,
                                               "end": truth.rhythm_end}, recording.clean_orientation))
            print_pose_row(rows[-1])
    for kind in RECORDING_KINDS:
        made = multi_session_pose_recording(2, kind, rng=np.random.default_rng(0))
        rows.append(pose_row(f"{kind} x2 0", made.t, made.Y, made.Q, None, made.clean_orientation))
        print_pose_row(rows[-1])
    summary("generated", rows)
    for path in sorted(args.data.rglob("*")) if args.data is not None else ():
        read = read_orientation(path, args.data_rate) if path.suffix.lower() in (".csv", ".txt") else None
        if read is not None:
            labels = path.with_suffix(".labels.json")
            user.append(pose_row(str(path.relative_to(args.data)), *read, _labels(labels) if labels.exists()
                                 else None))
            print_pose_row(user[-1])
    if user:
        summary("yours", user)
    _write("recordings_pose", rows, user, args.save)


def _session_rows(args: argparse.Namespace) -> None:
    """The session rows: 3 sessions of each kind (``--seeds`` seeds) against their truth, and the user's files."""
    rows, user = [], []
    with tempfile.TemporaryDirectory() as folder:
        for kind, seed, same in [(kind, seed, False) for kind in RECORDING_KINDS for seed in range(args.seeds)] \
                + [(kind, 0, True) for kind in RECORDING_KINDS]:        # one period: for the joint fit
            period = RECORDING_KINDS[kind].period
            made = multi_session_recording(3, kind, rng=np.random.default_rng(seed),
                                           periods=[period] * 3 if same else None)
            name = f"{kind} x3 {seed}" + (" one period" if same else "")
            csv_path = Path(folder) / f"{name.replace(' ', '-')}.csv"
            made.recording.to_csv(csv_path)
            demo = to_demonstration(made.recording.t, made.recording.Y, name=name)
            truth = [(s.onset, s.stop) for s in made.sessions]
            rows.append(session_row(name, demo, truth, csv_path))
            print_session_row(rows[-1])
        session_summary("generated", rows)
        for path, t, Y, _ in _user_recordings(args.data, args.data_rate) if args.data is not None else ():
            csv_path = Path(folder) / f"{path.stem}.csv"
            np.savetxt(csv_path, np.column_stack([t, Y]), delimiter=",", header="t,x,y,z", comments="")
            user.append(session_row(str(path.relative_to(args.data)), to_demonstration(t, Y, name=path.stem),
                                    _session_labels(path.with_suffix(".labels.json")), csv_path))
            print_session_row(user[-1])
        if user:
            session_summary("yours", user)
    out = results_dir(args.save) / "recordings_sessions.json"       # the --data rows too: the docs' table
    out.write_text(json.dumps({"generated": rows, "data": user}, indent=2, default=float) + "\n")
    print(f"wrote {out}")


def _summary(title: str, rows: list[dict]) -> None:
    """How many rows meet each target, and the worst figure."""
    fitted = [row for row in rows if "error" not in row]
    print(f"{title}: {len(fitted)} of {len(rows)} fitted, CLI ok on {sum(row['cli'] for row in rows)}")
    for key, limit in (("error_ratio", 1.5), ("start_error", 0.01), ("rest_error", 0.01),
                       ("acceleration_ratio", 1.5)):
        values = [row[key] for row in fitted if row.get(key) is not None]
        if values:
            print(f"  {key}: {sum(v <= limit for v in values)} of {len(values)} <= {limit:g} (worst {max(values):.4g})")
    for key in ("start_offset", "end_offset", "rest_offset"):
        values = [abs(row[key]) for row in fitted if key in row]
        if values:
            print(f"  |{key}|: max {max(values):.2f} s, median {np.median(values):.2f} s")


def _print(row: dict) -> None:
    if "error" in row:
        print(f"{row['recording']:>24}: FAILED ({row['error']}); CLI {'ok' if row['cli'] else 'failed'}")
        return
    truth = " ".join(f"{key[5:]} {row[key]:.2f}" for key in ("true_period", "true_start", "true_end", "true_rest")
                     if row.get(key) is not None)
    truth = f" (true: {truth})" if truth else ""
    rest, rest_error = ("-" if row[key] is None else f"{scale * row[key]:.{digits}f}{unit}"
                        for key, scale, digits, unit in (("rest", 1, 2, ""), ("rest_error", 1000, 1, " mm")))
    print(f"{row['recording']:>24}: period {row['period']:.3f} s, rhythm {row['start']:.2f}-{row['end']:.2f} s, "
          f"rest {rest}{truth} | cycle error {1000 * row['cycle_error']:.2f} mm / variation "
          f"{1000 * row['cycle_variation']:.2f} mm = {row['error_ratio']:.2f} | "
          f"start {1000 * row['start_error']:.1f} mm rest {rest_error} | "
          f"accel ratio {row['acceleration_ratio']:.2f}"
          + (f" (clean {row['clean_acceleration_ratio']:.2f})" if "clean_acceleration_ratio" in row else "") + " | "
          f"CLI {'ok' if row['cli'] else 'failed'}")


if __name__ == "__main__":
    sys.exit(main())
