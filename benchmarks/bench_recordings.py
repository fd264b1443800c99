"""Whole-recording fits: segmentation against the truth, cycle error against the recording's own cycle-to-cycle
variation, start and rest error, peak acceleration ratio, and whether ``rdmp-gym fit --demo`` succeeds.

By default on the realistic recordings of :mod:`rdmp_gym.recordings` (3 kinds x ``--seeds`` seeds); with
``--data PATH`` also on the user's own recordings (CSV files ``t,x,y,z`` under PATH, or the 12-column pose files
``*.txt`` of homogeneous transforms that some datasets ship, read at ``--data-rate`` Hz). Third-party data is read,
never copied. Targets: error ratio <= 1.5, start and rest error <= 1 cm, acceleration ratio <= 1.5.

    python benchmarks/bench_recordings.py [--seeds 3] [--data PATH --data-rate 100] [--save]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np
from output import add_save_argument, results_dir
from rdmp_gym.agents.cli import main as cli_main

from rdmp_gym.fitting import smooth_derivatives
from rdmp_gym.recording_fit import fit_recording, recording_report
from rdmp_gym.recordings import RECORDING_KINDS, realistic_recording, to_demonstration


def _row(name: str, demo, truth, csv_path: Path, clean=None) -> dict:
    """One table row; ``clean``: the noise-free recording (a Demonstration), where known."""
    row = {"recording": name, "duration": round(demo.duration, 2)}
    try:
        result = fit_recording(demo)
        seg = result.segmentation
        row.update(period=seg.period, start=seg.rhythm_start, end=seg.rhythm_end, rest=seg.rest_time,
                   **recording_report(demo, result))
    except ValueError as error:
        row["error"] = str(error)
    if truth is not None:
        row.update(true_period=truth.period, true_start=truth.rhythm_start, true_end=truth.rhythm_end,
                   true_rest=truth.rest_time)
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
    for path in sorted(folder.rglob("*")):
        if path.suffix.lower() == ".csv":
            data = np.genfromtxt(path, delimiter=",", names=True)
            names = data.dtype.names
            yield path, np.asarray(data[names[0]]), np.column_stack([data[n] for n in names[1:4]])
        elif path.suffix.lower() == ".txt":
            t, Y = _pose_file(path, rate)
            yield path, t, Y


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", type=int, default=3, help="seeds per kind of generated recording")
    parser.add_argument("--data", type=Path, default=None, help="a folder of the user's recordings (opt-in)")
    parser.add_argument("--data-rate", type=float, default=100.0, help="sampling rate of pose files without time")
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
                rows.append(_row(f"{kind} {seed}", demo, recording.truth, csv_path, clean))
                _print(rows[-1])
        generated = list(rows)
        if args.data is not None:
            for path, t, Y in _user_recordings(args.data, args.data_rate):
                csv_path = Path(folder) / f"user-{len(rows)}.csv"
                np.savetxt(csv_path, np.column_stack([t, Y]), delimiter=",", header="t,x,y,z", comments="")
                rows.append(_row(str(path.relative_to(args.data)), to_demonstration(t, Y), None, csv_path))
                _print(rows[-1])
    out = results_dir(args.save) / "recordings.json"
    out.write_text(json.dumps({"generated": generated}, indent=2, default=float) + "\n")
    print(f"wrote {out} (generated recordings only)")
    return 0


def _print(row: dict) -> None:
    if "error" in row:
        print(f"{row['recording']:>24}: FAILED ({row['error']}); CLI {'ok' if row['cli'] else 'failed'}")
        return
    truth = (f" (true {row['true_period']:.3f}, {row['true_start']:.2f}-{row['true_end']:.2f}, "
             f"{row['true_rest']:.2f})" if "true_period" in row else "")
    rest = "-" if row["rest"] is None else f"{row['rest']:.2f}"
    print(f"{row['recording']:>24}: period {row['period']:.3f} s, rhythm {row['start']:.2f}-{row['end']:.2f} s, "
          f"rest {rest}{truth} | cycle error {1000 * row['cycle_error']:.2f} mm / variation "
          f"{1000 * row['cycle_variation']:.2f} mm = {row['error_ratio']:.2f} | "
          f"start {1000 * row['start_error']:.1f} mm rest {1000 * row['rest_error']:.1f} mm | "
          f"accel ratio {row['acceleration_ratio']:.2f}"
          + (f" (clean {row['clean_acceleration_ratio']:.2f})" if "clean_acceleration_ratio" in row else "") + " | "
          f"CLI {'ok' if row['cli'] else 'failed'}")


if __name__ == "__main__":
    sys.exit(main())
