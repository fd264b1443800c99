"""The ``rdmp-gym`` command: ``train``, ``evaluate``, ``fit`` and ``main`` (the job of ``make run``).

Examples::

    rdmp-gym train --agent creps --updates 30 --rollouts 10 --seed 0 --out runs/creps
    rdmp-gym train --agent pi2 --updates 30 --rollouts 10 --seed 0 --out runs/pi2
    rdmp-gym train --out runs/pi2 --resume             # continue a killed run
    rdmp-gym evaluate runs/creps --episodes 20 --video     # final policy on the 20 test contexts
    rdmp-gym fit --demo recording.csv --time-column time --rate 100 --plot
    rdmp-gym main --out runs/main

``fit`` needs only the core install; ``train``, ``evaluate`` and ``main`` need the ``agents`` extra
(``pip install "rdmp-gym[agents]"``) and say so when it is missing.
"""

from __future__ import annotations

import argparse
import atexit
import importlib
import importlib.util
import json
import logging
import os
import shutil
import sys
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from rdmp_gym import __version__, save_dmp

from . import EXTRA_MODULES
from .errors import WorkerError

__all__ = ["main"]

logger = logging.getLogger(__name__)

WIPE_ID = "rdmp_gym/ArmarWipe-v1"
_EXTRA_HINT = 'pip install "rdmp-gym[agents]"'


class _HelpFormatter(argparse.RawDescriptionHelpFormatter):
    """Keeps the description's line breaks and appends ``(default: ...)`` to every option's help that
    does not already say what its default is."""

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        if (not action.option_strings or action.required or "default" in text
                or action.default is argparse.SUPPRESS):
            return text
        value = "off" if action.default is False else "%(default)s"
        return f"{text} (default: {value})"


def _missing_extra() -> str | None:
    """The first missing module of the ``agents`` extra that training needs, or None if all are there."""
    try:
        importlib.import_module("rdmp_gym.agents.training")
    except ModuleNotFoundError as error:
        if error.name and error.name.split(".")[0] in EXTRA_MODULES:
            return error.name
        raise
    return None


def _needs_extra(args: argparse.Namespace) -> None:
    raise ModuleNotFoundError(f"needs the agents extra (missing module {args.missing!r}): {_EXTRA_HINT}",
                              name=args.missing)

#: the task, learner and updates of ``rdmp-gym main`` (x 10 rollouts, 2000 episodes: about 5 minutes of
#: training on 2 cores), the learner that reached the validation target soonest in the benchmark: ``bbrl``
#: exploring the approach 3x wider, on the task executed with the hand's clearance from the cup
MAIN_ENV = "rdmp_gym/ArmarWipe-v2"
MAIN_ENV_OPTIONS = (("cup_clearance", 0.01),)
MAIN_AGENT = "bbrl"
MAIN_OPTIONS = (("sigma_factors", "approach=3"),)
MAIN_UPDATES = 200


def _key_value(text: str) -> tuple[str, Any]:
    """``KEY=VALUE`` with VALUE parsed as JSON when it can be (numbers, lists, true/false), else a string."""
    key, sep, raw = text.partition("=")
    if not sep or not key:
        raise argparse.ArgumentTypeError(f"expected KEY=VALUE, got {text!r}")
    try:
        return key, json.loads(raw)
    except json.JSONDecodeError:
        return key, raw


def _add_task_arguments(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("task")
    group.add_argument("--env", default=WIPE_ID, help="episodic env id (one step = one DMP rollout; "
                       "rdmp_gym/DMPTracking-v0 is a physics-free DMP task)")
    group.add_argument("--style", type=int, help="built-in demonstration style 1-4 (default: the env's)")
    group.add_argument("--demo", default="", help="a CSV/NPZ demonstration to imitate instead of --style, in the "
                       "table frame in metres (x, y on the table, z above it) (default: none)")
    group.add_argument("--time-column", default="t", help="name of the --demo CSV's time column (seconds)")
    group.add_argument("--rate", type=float, default=None, help="resample --demo onto an even grid at this rate "
                       "in Hz (default: keep the samples, which must be evenly spaced)")
    group.add_argument("--dmp", default="", help="a saved DMP (dmp.json, e.g. a run's refined DMP) to start from "
                       "instead of fitting (default: none)")
    group.add_argument("--groups", nargs="+", help="parameter groups to refine: periodic transient initial "
                       "amplitude (default: the env's)")
    group.add_argument("--n-periodic", type=int, help="periodic basis functions (default: the env's)")
    group.add_argument("--n-transient", type=int, help="transient basis functions (default: the env's)")
    group.add_argument("--duration", type=float, help="episode length in s (default: the env's)")
    group.add_argument("--env-option", type=_key_value, action="append", default=[], metavar="KEY=VALUE",
                       help="any other gym.make keyword (repeatable; default: none)")
    group.add_argument("--reset-option", type=_key_value, action="append", default=[], metavar="KEY=VALUE",
                       help="a reset option applied to every episode, e.g. to fix the context "
                       "(repeatable; default: none)")


def _env_kwargs(args: argparse.Namespace) -> dict[str, Any]:
    kwargs = {name: value for name, value in (("style", args.style), ("groups", args.groups),
                                              ("n_periodic", args.n_periodic), ("n_transient", args.n_transient),
                                              ("duration", args.duration)) if value is not None}
    if args.dmp:
        kwargs["dmp"] = str(Path(args.dmp).resolve())
    options = dict(args.env_option)              # a later entry of the same key replaces an earlier one
    clash = sorted(set(options) & set(kwargs))
    if clash:
        raise ValueError(f"--env-option: {clash[0]} is also given by its own flag")
    return {**kwargs, **options}


def _add_backend_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--backend", choices=("local", "ray"), default="local",
                        help="where the episodes run: local worker processes or Ray actors (pip install "
                             "'rdmp-gym[ray]'); the numbers are the same (default %(default)s)")
    parser.add_argument("--ray-address", default=None,
                        help="Ray cluster to join with --backend ray (default: $RAY_ADDRESS, else a new local "
                             "Ray instance with --workers CPUs)")


def _add_training_arguments(parser: argparse.ArgumentParser, updates: int, agent: bool, eval_episodes: int,
                            eval_every: int = 1) -> None:
    from .training import AGENTS, START_MODES

    if agent:
        parser.add_argument("--agent", choices=AGENTS, default="pi2", help="learner")
    parser.add_argument("--updates", type=int, default=updates, help="updates")
    parser.add_argument("--rollouts", type=int, default=10, help="episodes per update")
    parser.add_argument("--seed", type=int, default=0, help="run seed")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1,
                        help="worker processes (default: all cores, %(default)s)")
    _add_backend_arguments(parser)
    parser.add_argument("--option", type=_key_value, action="append", default=[], metavar="KEY=VALUE",
                        help="learner setting, e.g. sigma=0.2 decay=0.9 (repeatable; default: the learner's)")
    parser.add_argument("--start", choices=START_MODES, default="imitation", help="start of the search")
    parser.add_argument("--perturbation", type=float, default=0.3, help="std of the perturbed start")
    parser.add_argument("--eval-episodes", type=int, default=eval_episodes,
                        help="validation contexts the policy is evaluated on")
    parser.add_argument("--eval-every", type=int, default=eval_every, help="updates between policy evaluations")
    parser.add_argument("--resume", action="store_true", help="continue the run in --out from its checkpoint, with "
                        "its own config.json (flags only to extend --updates or change --workers)")
    _add_task_arguments(parser)


def _prepare_demo(args: argparse.Namespace) -> None:
    """With ``--time-column`` or ``--rate``, read ``--demo`` now and point ``args.demo`` at an even-grid copy
    in a temporary folder (removed at exit); the run copies it in as ``demo.npz``, so it holds the
    demonstration it was trained on."""
    if not args.demo or (args.time_column == "t" and args.rate is None):
        return
    from .imitation import load_demonstration

    demo = load_demonstration(args.demo, time_column=args.time_column, rate=args.rate)
    folder = Path(tempfile.mkdtemp(prefix="rdmp-gym-demo-"))
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    demo.to_npz(folder / "demo.npz")
    args.demo, args.time_column, args.rate = str(folder / "demo.npz"), "t", None


def _train_config(args: argparse.Namespace, agent: str) -> Any:
    from .learners import CONTEXTUAL
    from .training import TrainConfig

    _prepare_demo(args)
    return TrainConfig(agent=agent, updates=args.updates, rollouts=args.rollouts, seed=args.seed,
                       workers=args.workers, env_id=args.env, env_kwargs=_env_kwargs(args),
                       reset_options=dict(args.reset_option) or None, options=dict(args.option),
                       start=args.start, perturbation=args.perturbation, demo=args.demo,
                       eval_episodes=args.eval_episodes, eval_every=args.eval_every,
                       shared_context=agent not in CONTEXTUAL)


#: command-line flags that set a field of the run's config: ``dest -> (field, flag)``
_RUN_FLAGS = {"agent": ("agent", "--agent"), "updates": ("updates", "--updates"),
              "rollouts": ("rollouts", "--rollouts"), "seed": ("seed", "--seed"),
              "workers": ("workers", "--workers"), "start": ("start", "--start"),
              "perturbation": ("perturbation", "--perturbation"), "eval_episodes": ("eval_episodes", "--eval-episodes"),
              "eval_every": ("eval_every", "--eval-every"),
              "env": ("env_id", "--env"), "demo": ("demo", "--demo"), "style": ("env_kwargs.style", "--style"),
              "groups": ("env_kwargs.groups", "--groups"), "n_periodic": ("env_kwargs.n_periodic", "--n-periodic"),
              "n_transient": ("env_kwargs.n_transient", "--n-transient"),
              "duration": ("env_kwargs.duration", "--duration")}
_RUN_ENTRY_FLAGS = {"option": ("options", "--option"), "env_option": ("env_kwargs", "--env-option"),
                    "reset_option": ("reset_options", "--reset-option")}


def _all_actions(parser: argparse.ArgumentParser) -> list[argparse.Action]:
    actions = []
    for action in parser._actions:
        actions.append(action)
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                actions.extend(_all_actions(sub))
    return actions


def _given_flags(argv: Sequence[str]) -> set[str]:
    """The ``dest`` of every option written on the command line ``argv`` (defaults left out)."""
    parser = _parser()
    for action in _all_actions(parser):
        if action.option_strings:
            action.default = argparse.SUPPRESS
    return set(vars(parser.parse_known_args(argv)[0]))


def _resume_changes(args: argparse.Namespace) -> tuple[dict[str, Any], dict[str, str]]:
    """The settings given as flags to ``--resume`` (``field`` or ``field.key``) and their flag names."""
    changes, labels = {}, {}
    for dest in sorted(args.given_flags):
        if dest in _RUN_FLAGS:
            key, flag = _RUN_FLAGS[dest]
            changes[key], labels[key] = getattr(args, dest), flag
        elif dest in _RUN_ENTRY_FLAGS:
            field, flag = _RUN_ENTRY_FLAGS[dest]
            for name, value in getattr(args, dest):
                changes[f"{field}.{name}"], labels[f"{field}.{name}"] = value, f"{flag} {name}"
    return changes, labels


def _train_or_resume(args: argparse.Namespace, agent: str, out: Path | str) -> Any:
    """A new run from the flags, or (``--resume``) the run's own config changed only by the given flags."""
    from .training import train

    if args.resume:
        changes, labels = _resume_changes(args)
        return train(None, out, resume=True, changes=changes, labels=labels, progress=True,
                     backend=args.backend, ray_address=args.ray_address)
    return train(_train_config(args, agent), out, progress=True, backend=args.backend,
                 ray_address=args.ray_address)


def _command_train(args: argparse.Namespace) -> None:
    run = _train_or_resume(args, args.agent, args.out)
    last = run.read_log()[-1]
    print(f"{run.path}: {last['update']} updates, {last['episodes']} episodes, "
          f"best policy return {last['best_eval_return']:.4g}")
    if args.video:
        from .assessment import record_best_episode

        print(f"wrote {record_best_episode(run.path)}")


def _command_evaluate(args: argparse.Namespace) -> None:
    from .assessment import evaluate_run

    result = evaluate_run(args.run, args.episodes, workers=args.workers, policy=args.policy,
                          video=args.video, progress=True, backend=args.backend, ray_address=args.ray_address)
    _print_comparison(result)
    print(f"wrote {Path(args.run) / 'evaluation.json'} and evaluation.png" +
          (f" and {result['video']}" if "video" in result else ""))


def _command_fit(args: argparse.Namespace) -> None:
    from .imitation import fit_dmp, load_demonstration

    out = Path(args.out)
    if not args.demo:
        demo = load_demonstration(args.style)
        dmp = fit_dmp(demo, args.n_periodic, args.n_transient or 40, args.method)
        out.mkdir(parents=True, exist_ok=True)
        save_dmp(dmp, out / "dmp.json")
        reproduction = dmp.rollout(demo.t)
        rms = float(np.sqrt(np.mean(np.sum((demo.Y - reproduction) ** 2, axis=1))))
        print(f"{dmp}: RMS error {1000 * rms:.3f} mm over {demo.duration:.3g} s; wrote {out / 'dmp.json'}")
        if args.plot:
            from .plots import plot_fit

            plot_fit(demo.t - demo.t[0], demo.Y, reproduction, out / "fit.png",
                     title=f"{demo.name}: demonstration vs DMP")
            print(f"wrote {out / 'fit.png'}")
        return
    _fit_whole_recording(args, out)


def _fit_whole_recording(args: argparse.Namespace, out: Path) -> None:
    """``fit --demo``: the whole recording (rest, approach, rhythm, departure, rest) in one DMP."""
    from rdmp_gym import Demonstration
    from rdmp_gym.recording_fit import fit_recording, recording_report
    from rdmp_gym.recordings import despike

    from .imitation import load_demonstration

    loaded = load_demonstration(args.demo, time_column=args.time_column, rate=args.rate or 100.0)
    demo = Demonstration(loaded.t, despike(loaded.Y), name=loaded.name)
    result = fit_recording(demo, period=args.period, start=args.start, end=args.end, ending=args.ending,
                           n_periodic=args.n_periodic, method=args.method,
                           **({} if args.n_transient is None else {"n_transient": args.n_transient}))
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
    (out / "report.json").write_text(json.dumps({"period": seg.period, "rhythm_start": seg.rhythm_start,
                                                 "rhythm_end": seg.rhythm_end, "rest_time": seg.rest_time,
                                                 "stop_at": result.stop_at, **report}, indent=2) + "\n")
    print(f"wrote {out / 'dmp.json'} and {out / 'report.json'}")
    if args.plot:
        from .plots import plot_recording_fit

        plot_recording_fit(demo.t - demo.t[0], demo.Y, result.reproduce, out / "fit.png",
                           title=f"{demo.name}: recording vs DMP")
        print(f"wrote {out / 'fit.png'}")


def _interval_text(summary: dict[str, Any], metric: str) -> str:
    found = summary["intervals"].get(metric)
    return "-" if found is None else f"{found['estimate']:.3f} [{found['low']:.3f}, {found['high']:.3f}]"


def _print_comparison(result: dict[str, Any]) -> None:
    """Imitation vs trained on the test contexts: means with 95 % bootstrap intervals over the contexts."""
    print(f"{'policy':>10} {'success rate':>22} {'coverage':>22} {'jerk / imitation':>22}")
    for name in ("imitation", "trained"):
        summary = result[name]
        print(f"{name:>10} {_interval_text(summary, 'success'):>22} {_interval_text(summary, 'coverage'):>22} "
              f"{_interval_text(summary, 'jerk_ratio'):>22}")
    from .protocol import interval

    def paired_gain(metric: str) -> str:        # "-" where the task has no such metric (e.g. no dirt: coverage)
        gain = (np.array(result["trained"][metric], dtype=float)
                - np.array(result["imitation"][metric], dtype=float))
        return str(interval(gain, "mean")) if np.all(np.isfinite(gain)) else "-"

    print(f"paired gain over the imitation on the same {len(result['trained']['success'])} test contexts (mean, "
          f"95 % CI): coverage {paired_gain('coverage')}, success {paired_gain('success')}")
    for name in ("imitation", "trained"):
        if result[name].get("failures") is not None:
            print(f"{name} fails on: {_failure_text(result[name]['failures'])}")


def _failure_text(failures: list[str]) -> str:
    """``"cup 2 (contexts 3, 7), coverage 1 (context 3)"``: each missed success criterion, where it was missed."""
    from .tasks import failure_contexts

    return ", ".join(f"{cause} {len(found)} (context{'s' if len(found) > 1 else ''} "
                     f"{', '.join(map(str, found))})" for cause, found in failure_contexts(failures).items()) or "none"


def _command_main(args: argparse.Namespace) -> None:
    from rdmp_gym.figures import write_paper_figures

    from .assessment import evaluate_run
    from .imitation import fit_dmp, load_demonstration
    from .plots import plot_fit

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    config = _train_config(args, args.agent)
    style = config.env_kwargs.get("style", 1)
    demo = load_demonstration(args.demo if args.demo else style)
    print(f"[1/4] imitation: fitting the rhythmic DMP to {demo.name!r}")
    dmp = fit_dmp(demo, config.env_kwargs.get("n_periodic", 40), config.env_kwargs.get("n_transient", 40))
    plot_fit(demo.t - demo.t[0], demo.Y, dmp.rollout(demo.t), out / "fit.png", title=f"{demo.name}: imitation")
    print(f"[2/4] the paper's figures (2, 6, 7, 8, 9, 12) for the built-in demonstrations -> {out / 'figures'}")
    write_paper_figures(out / "figures")
    print(f"[3/4] {config.agent}: {config.updates} updates x {config.rollouts} rollouts on random training contexts, "
          f"{config.workers} worker(s); policy checked on {config.eval_episodes} validation contexts every "
          f"{config.eval_every} updates")
    run = _train_or_resume(args, config.agent, out / "train")
    curve = [(r["episodes"], r["eval_success"], r["eval_coverage"]) for r in run.read_log()
             if r.get("eval_coverage") is not None]
    print("held-out (validation) curve, episodes: success rate / coverage  " +
          "  ".join(f"{e}: {s:.2f}/{c:.3f}" for e, s, c in curve))
    print(f"[4/4] the final policy against the imitation on {args.episodes} test contexts (never trained on)")
    result = evaluate_run(run.path, args.episodes, workers=config.workers, policy="last", video=args.video,
                          progress=True)
    _print_comparison(result)
    summary = {"fit": str(out / "fit.png"), "figures": str(out / "figures"), "run": str(run.path),
               "learning_curve": str(run.curve_png), "validation_curve": curve,
               "evaluation": {name: {k: v for k, v in result[name].items()
                                     if k.endswith(("_mean", "_fraction", "_rate")) or k == "intervals"}
                              for name in ("imitation", "trained")}}
    (out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    print(f"wrote {out / 'summary.json'}, {out / 'fit.png'}, {run.curve_png}, {run.path / 'evaluation.png'}")


def _add_agents_commands(commands: Any) -> None:
    """``train``, ``evaluate`` and ``main``; when the ``agents`` extra is missing, stand-ins that say so."""
    missing = _missing_extra()
    about = {"train": "train an agent (creps, cpi2, pi2, pibb, cmaes, ppo, sac, ...)",
             "evaluate": "evaluate a run's final policy against the imitation on the test contexts",
             "main": "imitation, contextual refinement and evaluation on test contexts, end to end"}
    if missing is not None:
        for name, text in about.items():
            stub = commands.add_parser(name, help=f"{text} [needs the agents extra]", add_help=False)
            stub.set_defaults(handler=_needs_extra, missing=missing)
        return

    train = commands.add_parser("train", help=about["train"], formatter_class=_HelpFormatter)
    train.add_argument("--out", required=True, help="run directory (required)")
    train.add_argument("--video", action="store_true", help="record the best policy's episode (best_episode.mp4)")
    _add_training_arguments(train, updates=30, agent=True, eval_episodes=1)
    train.set_defaults(handler=_command_train)

    evaluate = commands.add_parser("evaluate", help=about["evaluate"], formatter_class=_HelpFormatter)
    evaluate.add_argument("run", help="run directory")
    evaluate.add_argument("--episodes", type=int, default=20, help="test contexts")
    evaluate.add_argument("--workers", type=int, default=os.cpu_count() or 1, help="worker processes")
    evaluate.add_argument("--policy", choices=("last", "best"), default="last",
                          help="the final policy (default) or the best on the validation contexts (shared θ only)")
    _add_backend_arguments(evaluate)
    evaluate.add_argument("--video", action="store_true", help="record the best episode (best_episode.mp4)")
    evaluate.set_defaults(handler=_command_evaluate)

    job = commands.add_parser("main", help=about["main"], formatter_class=_HelpFormatter,
                              description=f"{about['main']}. Defaults beyond the flags' own: " +
                              " ".join(f"--env-option {k}={v}" for k, v in MAIN_ENV_OPTIONS) + " " +
                              " ".join(f"--option {k}={v}" for k, v in MAIN_OPTIONS) +
                              " (a given --option or --env-option of the same key replaces it; "
                              "--env-option cup_clearance=null turns the clearance off).")
    job.add_argument("--out", default="runs/main", help="output directory")
    job.add_argument("--episodes", type=int, default=20, help="test contexts")
    job.add_argument("--video", action="store_true", help="record the best evaluation episode")
    job.add_argument("--agent", default=MAIN_AGENT, help="learner")
    _add_training_arguments(job, updates=MAIN_UPDATES, agent=False, eval_episodes=8, eval_every=20)
    job.set_defaults(env=MAIN_ENV, env_option=list(MAIN_ENV_OPTIONS), option=list(MAIN_OPTIONS))
    job.set_defaults(handler=_command_main)


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="rdmp-gym", description=__doc__, formatter_class=_HelpFormatter)
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress details")
    commands = parser.add_subparsers(dest="command", required=True)

    fit = commands.add_parser("fit", help="fit the rhythmic DMP to a whole recording: rest, approach, rhythm, "
                              "departure, rest (core install)",
                              formatter_class=_HelpFormatter)
    fit.add_argument("--style", type=int, default=1, help="built-in demonstration style 1-4")
    fit.add_argument("--demo", default="", help="a CSV/NPZ demonstration instead of --style (default: none)")
    fit.add_argument("--time-column", default="t", help="name of the CSV's time column (seconds)")
    fit.add_argument("--rate", type=float, default=None,
                     help="resample --demo onto an even grid at this rate in Hz; uneven time stamps are always "
                     "resampled, outliers removed first (default: 100 Hz)")
    fit.add_argument("--n-periodic", type=int, default=40, help="periodic basis functions")
    fit.add_argument("--n-transient", type=int, default=None,
                     help="transient basis functions (default: 40 for --style, 20 for the entry into the rhythm of a "
                     "whole --demo recording)")
    fit.add_argument("--method", choices=("trajectory", "ridge", "lwr"), default="trajectory",
                     help="regression (trajectory: the rollout itself matches the samples)")
    fit.add_argument("--period", type=float, default=None, help="the rhythm's period in s (default: detected)")
    fit.add_argument("--start", type=float, default=None,
                     help="time (s from the first sample) from which the rhythm runs at full size (default: detected)")
    fit.add_argument("--end", type=float, default=None, help="time (s) at which the rhythm ends (default: detected)")
    fit.add_argument("--ending", action=argparse.BooleanOptionalAction, default=None,
                     help="fit the departure and the final rest as the DMP's stop (default: where the recording "
                     "ends at rest)")
    fit.add_argument("--plot", action="store_true",
                     help="write fit.png (recording vs reproduction: position and acceleration)")
    fit.add_argument("--out", default="runs/fit", help="output directory")
    fit.set_defaults(handler=_command_fit)

    _add_agents_commands(commands)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``rdmp-gym``; returns the exit status."""
    parser = _parser()
    args, unknown = parser.parse_known_args(argv)
    if unknown and args.handler is not _needs_extra:   # the stand-ins take any arguments
        parser.error(f"unrecognized arguments: {' '.join(unknown)}")
    args.given_flags = _given_flags(sys.argv[1:] if argv is None else argv)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING,
                        format="%(levelname)s %(name)s: %(message)s")
    try:
        if getattr(args, "video", False) and not os.environ.get("MUJOCO_GL") and not os.environ.get("DISPLAY"):
            raise ValueError("--video: no display; run with MUJOCO_GL=egl (or osmesa) set in the environment")
        if args.command != "fit" and importlib.util.find_spec("torch") is not None:
            import torch

            torch.set_num_threads(1)
        args.handler(args)
    except ModuleNotFoundError as error:
        if not error.name or error.name.split(".")[0] not in EXTRA_MODULES:
            raise
        print(f"rdmp-gym {args.command}: error: {error}" + ("" if "extra" in str(error) else
              f"; it comes with the agents extra: {_EXTRA_HINT}"), file=sys.stderr)
        return 2
    except (ValueError, TypeError, OSError, FloatingPointError, ImportError, WorkerError) as error:
        print(f"rdmp-gym {args.command}: error: {error}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
