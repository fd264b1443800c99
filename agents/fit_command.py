"""``rdmp-gym fit``: the rhythmic DMP fitted to a built-in style or to a whole recording. Needs only the core
install (and the ``plots`` extra for ``--plot``)."""

from __future__ import annotations

import contextlib
import json
import logging
import re
import shutil
import tempfile
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Literal

import numpy as np
import tyro

from rdmp_gym import Demonstration, save_dmp
from rdmp_gym.recordings.pose_io import read_pose_csv
from rdmp_gym.recordings.recording_fit import constant_columns, fit_recording, recording_report
from rdmp_gym.signals.filters import despike
from rdmp_gym.signals.segmentation.sessions import Session

from .fit_pose import constant_note, fit_pose_command
from .fit_sessions import fit_joint_command, fit_pose_sessions_command, fit_sessions_command, several_sessions
from .imitation import fit_dmp, load_demonstration

__all__ = ["FitCommand", "command_fit", "parse_fit"]


@dataclass
class FitCommand:
    """Fit the rhythmic DMP to a built-in style or to a whole recording (rest, approach, rhythm, departure, rest)."""

    style: int = 1
    """built-in demonstration style 1-4"""
    demo: str = ""
    """a CSV/NPZ demonstration instead of --style (default: none); a CSV with columns qw, qx, qy, qz beside the
    position is fitted as a pose (position and orientation)"""
    time_column: str = "t"
    """name of the CSV's time column (seconds)"""
    rate: float | None = None
    """resample --demo onto an even grid at this rate in Hz (default: 100 Hz)"""
    n_periodic: int = 40
    """periodic basis functions"""
    n_transient: int | None = None
    """transient basis functions (default: 40 for --style, 20 for the entry of a whole --demo recording)"""
    method: Literal["trajectory", "ridge", "lwr"] = "trajectory"
    """regression (trajectory: the rollout itself matches the samples)"""
    period: float | None = None
    """the rhythm's period in s (default: detected)"""
    start: float | None = None
    """time (s from the first sample) from which the rhythm runs at full size (default: detected)"""
    end: float | None = None
    """time (s) at which the rhythm ends (default: detected)"""
    ending: bool | None = None
    """fit the departure and the final rest as the DMP's stop (default: where the recording ends at rest)"""
    sessions: Literal["split", "joint", "off"] = "split"
    """a recording with several sessions (rhythms separated by departures or rests): split (one DMP each: dmp-1.json,
    dmp-2.json, ...), joint (one DMP for all, their mean rhythm, with each session's anchor in report.json), off
    (one DMP for the whole recording, as for one session; also with a --period/--start/--end hint)"""
    plot: bool = False
    """write fit.png (recording vs reproduction: position and acceleration; needs the plots extra)"""
    out: str = "runs/fit"
    """output directory (refused when it already holds a fit: dmp*.json, report.json, fit*.png)"""
    overwrite: bool = False
    """replace a fit already in --out: once the new fit is written, the earlier fit's files it did not rewrite
    (dmp-3.json of a recording with more sessions, ...) are removed; if the new fit fails, the earlier one is put
    back"""
    verbose: bool = False
    """log progress details"""


def parse_fit(argv: Sequence[str]) -> FitCommand:
    """The ``fit`` command line parsed into its :class:`FitCommand`, without running it."""
    return tyro.cli(FitCommand, args=argv, prog="rdmp-gym fit")


def command_fit(argv: Sequence[str]) -> None:
    """``rdmp-gym fit ARGS``: write ``dmp.json`` (and ``fit.png`` with ``--plot``) into ``--out``."""
    args = parse_fit(argv)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING,
                        format="%(levelname)s %(name)s: %(message)s")
    out = Path(args.out)
    with _fit_directory(out, args.overwrite):
        _fit(args, out)


#: the files a fit writes into --out: dmp.json or dmp-K.json, report.json, fit.png or fit-K.png
_FIT_FILE = re.compile(r"(dmp(-\d+)?\.json|report\.json|fit(-\d+)?\.png)")


def _fit_files(out: Path) -> list[Path]:
    """The files of a fit in ``out`` (none where it does not exist), by name."""
    if not out.is_dir():
        return []
    return sorted(path for path in out.iterdir() if _FIT_FILE.fullmatch(path.name) and not path.is_dir())


@contextlib.contextmanager
def _fit_directory(out: Path, overwrite: bool) -> Iterator[None]:
    """Refuse an ``out`` that already holds a fit unless ``overwrite``; with ``overwrite``, set the earlier fit's
    files aside while the new fit is written, then remove them (or, if the new fit fails, remove what it wrote
    and put them back)."""
    if out.exists() and not out.is_dir():
        raise FileExistsError(f"out: {out} is a file, not a directory; choose another --out")
    previous = _fit_files(out)
    if previous and not overwrite:
        shown = ", ".join(path.name for path in previous[:5]) + (", ..." if len(previous) > 5 else "")
        raise FileExistsError(f"out: {out} already holds a fit ({shown}); pass --overwrite to replace it or choose "
                              "another --out")
    if not previous:
        yield
        return
    aside = Path(tempfile.mkdtemp(prefix=".earlier-fit-", dir=out))
    for path in previous:
        path.rename(aside / path.name)
    try:
        yield
    except BaseException:
        for path in _fit_files(out):                # what the failed fit wrote
            path.unlink()
        for path in previous:
            (aside / path.name).rename(path)
        aside.rmdir()
        raise
    shutil.rmtree(aside)


def _fit(args: FitCommand, out: Path) -> None:
    """Fit as ``args`` say and write the fit into ``out``."""
    plots = _plots() if args.plot else None
    if args.demo:
        _fit_whole_recording(args, out, plots)
        return
    demo = load_demonstration(args.style)
    dmp = fit_dmp(demo, args.n_periodic, args.n_transient or 40, args.method)
    out.mkdir(parents=True, exist_ok=True)
    save_dmp(dmp, out / "dmp.json")
    reproduction = dmp.rollout(demo.t)
    rms = float(np.sqrt(np.mean(np.sum((demo.Y - reproduction) ** 2, axis=1))))
    print(f"{dmp}: RMS error {1000 * rms:.3f} mm over {demo.duration:.3g} s; wrote {out / 'dmp.json'}")
    if plots is not None:
        plots.plot_fit(demo.t - demo.t[0], demo.Y, reproduction, out / "fit.png",
                       title=f"{demo.name}: demonstration vs DMP")
        print(f"wrote {out / 'fit.png'}")


def _plots() -> ModuleType:
    """The figures module (matplotlib: the ``plots`` extra; an ``ImportError`` naming it when missing)."""
    try:
        from . import plots  # matplotlib: the plots extra
    except ModuleNotFoundError as error:
        raise ImportError(f"--plot: needs the plots extra (missing module {error.name!r}): "
                          'pip install "rdmp-gym[plots]"') from error
    return plots


def _sessions(args: FitCommand, demo: Demonstration, pose: bool) -> list[Session] | None:
    """The sessions of ``demo`` to fit one by one or together, or ``None`` for one fit of the whole recording
    (one session found, ``--sessions off``, or a hint of one rhythm)."""
    one_rhythm = (args.period, args.start, args.end) != (None, None, None)
    if one_rhythm and args.sessions == "joint":
        raise ValueError("--sessions joint: fits several sessions; --period, --start and --end are hints for one "
                         "rhythm (use --sessions off with them)")
    sessions = several_sessions(demo) if args.sessions != "off" and not one_rhythm else None
    if sessions is not None and pose and args.sessions == "joint":
        raise ValueError(f"--sessions joint: fits the position of several sessions as one rhythm; the pose "
                         f"recording {demo.name!r} has {len(sessions)} sessions, fitted one pose DMP each with "
                         "--sessions split")
    return sessions


def _fit_whole_recording(args: FitCommand, out: Path, plots: ModuleType | None) -> None:
    """``fit --demo``: the whole recording (rest, approach, rhythm, departure, rest) in one DMP; a CSV with the
    orientation columns ``qw, qx, qy, qz`` is fitted as a pose (:mod:`.fit_pose`)."""
    hints = dict(period=args.period, start=args.start, end=args.end, ending=args.ending, n_periodic=args.n_periodic,
                 method=args.method, **({} if args.n_transient is None else {"n_transient": args.n_transient}))
    path = Path(args.demo)
    pose = read_pose_csv(path, args.time_column, args.rate or 100.0) if path.suffix.lower() == ".csv" \
        and path.is_file() else None
    if pose is None:
        loaded = load_demonstration(args.demo, time_column=args.time_column, rate=args.rate or 100.0)
        demo = Demonstration(loaded.t, despike(loaded.Y), name=loaded.name)
    else:
        demo = pose.position
    sessions = _sessions(args, demo, pose is not None)
    if sessions is not None:
        if pose is not None:
            fit_pose_sessions_command(pose, sessions, hints, out, plots)
        else:
            (fit_joint_command if args.sessions == "joint" else fit_sessions_command)(demo, sessions, hints, out,
                                                                                      plots)
        return
    if pose is not None:
        fit_pose_command(pose, hints, out, plots)
    else:
        _fit_one_rhythm(demo, hints, out, plots)


def _fit_one_rhythm(demo: Demonstration, hints: dict, out: Path, plots: ModuleType | None) -> None:
    """One DMP for the whole position recording ``demo``: write ``dmp.json``, ``report.json`` (and ``fit.png``)."""
    result = fit_recording(demo, **hints)
    out.mkdir(parents=True, exist_ok=True)
    save_dmp(result.dmp, out / "dmp.json")
    seg, report = result.segmentation, recording_report(demo, result)
    rest = "no final rest" if seg.rest_time is None else f"at rest from {seg.rest_time:.2f} s"
    print(f"{demo.name}: period {seg.period:.3f} s, rhythm {seg.rhythm_start:.2f}-{seg.rhythm_end:.2f} s, {rest}")
    rest_error = "-" if report["rest_error"] is None else f"{1000 * report['rest_error']:.2f} mm"
    print(f"cycle error {1000 * report['cycle_error']:.2f} mm vs cycle-to-cycle variation "
          f"{1000 * report['cycle_variation']:.2f} mm (x{report['error_ratio']:.2f}); start error "
          f"{1000 * report['start_error']:.2f} mm, rest error {rest_error}; peak acceleration "
          f"{report['peak_acceleration']:.2f} m/s^2 vs {report['recording_peak_acceleration']:.2f} (smoothed "
          f"recording, x{report['acceleration_ratio']:.2f})")
    constant = constant_columns(demo.Y)
    if constant:
        print(constant_note(constant))
    (out / "report.json").write_text(json.dumps({"period": seg.period, "rhythm_start": seg.rhythm_start,
                                                 "rhythm_end": seg.rhythm_end, "rest_time": seg.rest_time,
                                                 "stop_at": result.stop_at, **report, "constant_columns": constant},
                                                indent=2) + "\n")
    print(f"wrote {out / 'dmp.json'} and {out / 'report.json'}")
    if plots is not None:
        plots.plot_recording_fit(demo.t - demo.t[0], demo.Y, result.reproduce, out / "fit.png",
                           title=f"{demo.name}: recording vs DMP")
        print(f"wrote {out / 'fit.png'}")

