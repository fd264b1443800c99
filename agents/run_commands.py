"""``rdmp-gym train``, ``evaluate`` and ``main`` (the job of ``make run``); they need the ``agents`` extra.

Every command's flags are derived with `tyro <https://brentyi.github.io/tyro/>`_ from typed dataclasses: the
run's (:class:`TrainCommand`), the task's (:class:`TaskFlags`) and the chosen learner's settings
(``--options.NAME``, the fields of its settings class, e.g. :class:`~rdmp_gym.agents.learners.bbrl_config.BBRLConfig`)::

    rdmp-gym train --out runs/bbrl                      # the main job's learner (bbrl) on the current task
    rdmp-gym train --agent cpi2 --updates 30 --options.sigma 0.2 --out runs/cpi2
    rdmp-gym train --agent bbrl --options.sigma-factors approach 3 amplitude 2 --out runs/wide
    rdmp-gym train --out runs/bbrl --resume --updates 300       # continue (and extend) a run
    rdmp-gym evaluate runs/bbrl --episodes 20 --video   # final policy on the 20 test contexts
    rdmp-gym main --out runs/main

A run saves its configuration as ``config.json``; ``--resume`` reads it back and applies only the flags given
(``--updates`` and ``--workers`` may change, any other differing setting is an error naming it). The launcher
:mod:`rdmp_gym.agents.cli` calls :func:`command_train`, :func:`command_evaluate` and :func:`command_main`.
"""

from __future__ import annotations

import atexit
import dataclasses
import json
import logging
import os
import shutil
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np
import tyro

from rdmp_gym.figures.paper import write_paper_figures

from .config import Settings
from .imitation import load_demonstration
from .plots import plot_fit
from .protocol import interval
from .report import evaluate_run, record_best_episode
from .runs import RunDirectory
from .tasks import failure_contexts, main_env_kwargs, main_options
from .train_config import AGENTS, START_MODES, TrainConfig
from .training import MUTABLE_ON_RESUME, load_run_config, train

__all__ = ["EvaluateCommand", "MainCommand", "TaskFlags", "TrainCommand", "command_evaluate", "command_main",
           "command_train", "parse_evaluate", "parse_main", "parse_train", "train_config"]

logger = logging.getLogger(__name__)

#: a ``gym.make`` keyword's or reset option's value on the command line (``None`` for null)
EnvValue = bool | int | float | str | None
_WORKERS = os.cpu_count() or 1
#: the run's defaults, defined once by :class:`TrainConfig` (the main learner on the current task)
_RUN = {item.name: item.default for item in dataclasses.fields(TrainConfig)}


@dataclass
class TaskFlags:
    """The task: the env and its ``gym.make`` keywords."""

    env: str = _RUN["env_id"]
    """episodic env id (one step = one DMP rollout); rdmp_gym/DMPTracking-v0 is a physics-free DMP task"""
    style: int | None = None
    """built-in demonstration style 1-4 (default: the env's)"""
    demo: str = ""
    """a CSV/NPZ demonstration to imitate instead of --style, in the table frame in metres (default: none)"""
    time_column: str = "t"
    """name of the --demo CSV's time column (seconds)"""
    rate: float | None = None
    """resample --demo onto an even grid at this rate in Hz (default: keep the samples, evenly spaced)"""
    dmp: str = ""
    """a saved DMP (dmp.json, e.g. a run's refined DMP) to start from instead of fitting (default: none)"""
    groups: tuple[str, ...] | None = None
    """parameter groups to refine: periodic transient initial amplitude (default: the env's)"""
    n_periodic: int | None = None
    """periodic basis functions (default: the env's)"""
    n_transient: int | None = None
    """transient basis functions (default: the env's)"""
    duration: float | None = None
    """episode length in s (default: the env's)"""
    env_option: dict[str, EnvValue] = field(default_factory=dict)
    """any other gym.make keyword, KEY VALUE pairs (on the main job's env: cup_clearance 0.01 unless given;
    cup_clearance None turns the clearance off)"""
    reset_option: dict[str, EnvValue] = field(default_factory=dict)
    """reset options for every episode, KEY VALUE pairs (e.g. to fix the context)"""


@dataclass
class TrainCommand(TaskFlags):
    """Train an agent: bbrl with the main job's settings on the current task unless --agent / --env say otherwise."""

    out: str = ""
    """run directory (required)"""
    agent: Literal[AGENTS] = _RUN["agent"]  # type: ignore[valid-type]
    """learner; its settings are --options.NAME flags (see --agent NAME --help)"""
    updates: int = _RUN["updates"]
    """updates"""
    rollouts: int = _RUN["rollouts"]
    """episodes per update"""
    seed: int = _RUN["seed"]
    """run seed"""
    workers: int = _WORKERS
    """worker processes (the numbers do not depend on it)"""
    backend: Literal["local", "ray"] = "local"
    """where the episodes run: local worker processes or Ray actors (the numbers are the same)"""
    ray_address: str | None = None
    """Ray cluster to join with --backend ray (default: $RAY_ADDRESS, else a new local Ray instance)"""
    start: Literal[START_MODES] = _RUN["start"]  # type: ignore[valid-type]
    """start of the search"""
    perturbation: float = _RUN["perturbation"]
    """std of the perturbed start"""
    eval_episodes: int = _RUN["eval_episodes"]
    """validation contexts the policy is evaluated on"""
    eval_every: int = _RUN["eval_every"]
    """updates between policy evaluations"""
    stratified_validation: bool = _RUN["stratified_validation"]
    """spread the validation contexts evenly over the kinds of context the env names (e.g. cup on the approach)"""
    resume: bool = False
    """continue the run in --out from its checkpoint with its own config.json (flags only to change it)"""
    video: bool = False
    """record the best policy's episode (best_episode.mp4)"""
    verbose: bool = False
    """log progress details"""

    @property
    def run_path(self) -> Path:
        """The run directory the command trains (and ``--resume`` continues)."""
        return Path(self.out)


@dataclass
class MainCommand(TrainCommand):
    """Imitation, the paper's figures, contextual refinement and evaluation on test contexts, end to end."""

    out: str = "runs/main"
    """output directory"""
    updates: int = 200
    eval_episodes: int = 8
    eval_every: int = 20
    episodes: int = 20
    """test contexts"""

    @property
    def run_path(self) -> Path:
        """The run directory: ``train`` in the output directory."""
        return Path(self.out) / "train"


@dataclass
class EvaluateCommand:
    """Evaluate a run's final policy against the imitation on the test contexts."""

    run: tyro.conf.Positional[str]
    """run directory"""
    episodes: int = 20
    """test contexts"""
    workers: int = _WORKERS
    """worker processes"""
    policy: Literal["last", "best"] = "last"
    """the final policy or the best on the validation contexts (shared θ only)"""
    backend: Literal["local", "ray"] = "local"
    """where the episodes run"""
    ray_address: str | None = None
    """Ray cluster to join with --backend ray"""
    video: bool = False
    """record the best episode (best_episode.mp4)"""
    verbose: bool = False
    """log progress details"""


def _env_kwargs(task: TaskFlags) -> dict[str, Any]:
    """The ``gym.make`` keywords of the task flags (the main job's env keywords under them on its env)."""
    kwargs = {name: getattr(task, name) for name in ("style", "n_periodic", "n_transient", "duration")
              if getattr(task, name) is not None}
    if task.groups is not None:
        kwargs["groups"] = list(task.groups)
    if task.dmp:
        kwargs["dmp"] = str(Path(task.dmp).resolve())
    clash = sorted(set(task.env_option) & set(kwargs))
    if clash:
        raise ValueError(f"--env-option: {clash[0]} is also given by its own flag")
    return {**main_env_kwargs(task.env), **kwargs, **task.env_option}


def _prepare_demo(task: TaskFlags) -> str:
    """``--demo``, or with ``--time-column``/``--rate`` an even-grid copy of it in a temporary folder (removed at
    exit); the run copies it in as ``demo.npz``, so it holds the demonstration it was trained on."""
    if not task.demo or (task.time_column == "t" and task.rate is None):
        return task.demo
    demo = load_demonstration(task.demo, time_column=task.time_column, rate=task.rate)
    folder = Path(tempfile.mkdtemp(prefix="rdmp-gym-demo-"))
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    demo.to_npz(folder / "demo.npz")
    return str(folder / "demo.npz")


def train_config(command: TrainCommand, options: Settings | None = None) -> TrainConfig:
    """The training run of a ``train``/``main`` command (``options``: the learner's settings; default: the task's
    defaults for the agent, the main job's options for its learner)."""
    return TrainConfig(agent=command.agent, updates=command.updates, rollouts=command.rollouts, seed=command.seed,
                       workers=command.workers, env_id=command.env, env_kwargs=_env_kwargs(command),
                       reset_options=dict(command.reset_option) or None,
                       options=_default_options(command) if options is None else options, start=command.start,
                       perturbation=command.perturbation, demo=_prepare_demo(command),
                       eval_episodes=command.eval_episodes, eval_every=command.eval_every,
                       stratified_validation=command.stratified_validation)


def _default_options(command: TrainCommand) -> Settings:
    """The learner's settings of a new run: the task's defaults for the agent (the main job's for its learner)."""
    return TrainConfig(agent=command.agent, env_id=command.env, env_kwargs=_env_kwargs(command),
                       options=main_options(command.agent, command.env)).options


_TASK_FLAGS = ("style", "n_periodic", "n_transient", "duration", "groups", "dmp")
_FLAG_NAMES = {"env_id": "--env"}


def _saved_command(kind: type[TrainCommand], saved: TrainConfig, out: str) -> TrainCommand:
    """The command whose flags rebuild ``saved`` (a resumed run's defaults, so that only given flags change it)."""
    env_kwargs = dict(saved.env_kwargs)
    flags = {name: env_kwargs.pop(name) for name in _TASK_FLAGS if name in env_kwargs}
    if "groups" in flags:
        flags["groups"] = tuple(flags["groups"])
    for key, value in main_env_kwargs(saved.env_id).items():  # the main job's keywords come back as defaults
        if env_kwargs.get(key, object()) == value:
            env_kwargs.pop(key)
    return kind(env=saved.env_id, demo=saved.demo, env_option=env_kwargs, reset_option=dict(saved.reset_options or {}),
                out=out, agent=saved.agent, updates=saved.updates, rollouts=saved.rollouts, seed=saved.seed,
                workers=saved.workers, start=saved.start, perturbation=saved.perturbation,
                eval_episodes=saved.eval_episodes, eval_every=saved.eval_every,
                stratified_validation=saved.stratified_validation, resume=True, **flags)


def _parse_flags(kind: type[TrainCommand], argv: Sequence[str], prog: str, *, read_run: bool = True
                 ) -> tuple[TrainCommand, TrainConfig | None]:
    """Parse a ``train``/``main`` command line into the command, with the learner's settings as ``options``, and
    (for ``--resume`` with ``read_run``) the saved run it continues.

    The agent (and for ``--resume`` the saved run) decides which learner settings exist, so a first pass reads
    the run's flags and a second parses everything, the learner's ``--options.NAME`` flags included, with the
    defaults of the task (or of the saved run). Dict settings (``sigma_factors``) add to the defaults'. Without
    ``read_run`` a ``--resume`` line is parsed over the task's defaults (no run directory is read).
    """
    first = tyro.cli(kind, args=argv, prog=prog, add_help=False, return_unknown_args=True)[0]
    read_run = read_run and first.resume
    if read_run and not first.out:
        raise ValueError("--out: the run directory is required")
    saved = load_run_config(RunDirectory(first.run_path)) if read_run else None
    if saved is not None:
        defaults, options = _saved_command(kind, saved, first.out), saved.options
    else:
        defaults, options = first, _default_options(first)
    dicts = {item.name: getattr(options, item.name) for item in dataclasses.fields(options)
             if isinstance(getattr(options, item.name), dict)}
    flags = dataclasses.make_dataclass(kind.__name__, [("options", type(options), field(default=None))],
                                       bases=(kind,))
    flags.__module__ = kind.__module__
    values = {item.name: getattr(defaults, item.name) for item in dataclasses.fields(kind)}
    start = flags(**{**values, "env_option": {}, "reset_option": {}},      # tyro fixes the keys of a given dict
                  options=dataclasses.replace(options, **{key: {} for key in dicts}))
    parsed = tyro.cli(flags, args=argv, prog=prog, default=start, description=kind.__doc__)
    given = dataclasses.replace(parsed.options, **{name: {**value, **getattr(parsed.options, name)}
                                                   for name, value in dicts.items()})
    command = flags(**{**{item.name: getattr(parsed, item.name) for item in dataclasses.fields(kind)},
                       **{name: {**values[name], **getattr(parsed, name)} for name in ("env_option", "reset_option")}},
                    options=given)
    if not command.out:
        raise ValueError("--out: the run directory is required")
    return command, saved


def parse_train(argv: Sequence[str]) -> TrainCommand:
    """The ``train`` command line parsed into its :class:`TrainCommand` (the learner's settings as ``options``),
    without running it or reading a run directory (a ``--resume`` line is parsed over the task's defaults)."""
    return _parse_flags(TrainCommand, argv, "rdmp-gym train", read_run=False)[0]


def parse_main(argv: Sequence[str]) -> MainCommand:
    """The ``main`` command line parsed into its :class:`MainCommand`, without running it (see :func:`parse_train`)."""
    return _parse_flags(MainCommand, argv, "rdmp-gym main", read_run=False)[0]  # type: ignore[return-value]


def parse_evaluate(argv: Sequence[str]) -> EvaluateCommand:
    """The ``evaluate`` command line parsed into its :class:`EvaluateCommand`, without running it."""
    return tyro.cli(EvaluateCommand, args=argv, prog="rdmp-gym evaluate")


def _flag(key: str) -> str:
    """The command-line flag of a setting of the run (``key``: a field, or ``field.entry`` of a dict field)."""
    name, _, entry = key.partition(".")
    if not entry:
        return _FLAG_NAMES.get(name, "--" + name.replace("_", "-"))
    if name == "options":
        return "--options." + entry.replace("_", "-")
    if name == "env_kwargs":
        return "--" + entry.replace("_", "-") if entry in _TASK_FLAGS else f"--env-option {entry}"
    return f"--reset-option {entry}"


def _resume_changes(saved: TrainConfig, config: TrainConfig) -> dict[str, Any]:
    """What the flags of a resumed run change in its saved configuration: ``updates`` and ``workers`` always, every
    other field (or entry of a dict field) only where it differs, keyed as :func:`train` takes ``changes``."""
    before, after = saved.to_dict(), config.to_dict()
    changes: dict[str, Any] = {}
    for name, value in after.items():
        if name in ("env_kwargs", "options", "reset_options"):
            old = before[name] or {}
            changes.update({f"{name}.{key}": entry for key, entry in (value or {}).items() if old.get(key) != entry})
        elif name in MUTABLE_ON_RESUME or value != before[name]:
            changes[name] = value
    return changes


def _parse_run(kind: type[TrainCommand], argv: Sequence[str], prog: str
               ) -> tuple[TrainCommand, TrainConfig, TrainConfig | None]:
    """A ``train``/``main`` command line: the command, its training run and (``--resume``) the saved run."""
    command, saved = _parse_flags(kind, argv, prog)
    if saved is not None and command.agent != saved.agent:      # the run's learner settings are its agent's
        raise ValueError(f"--agent: {command.agent!r} differs from the run's {saved.agent!r} "
                         f"({RunDirectory(command.run_path).config_path}); a resumed run keeps its configuration, "
                         f"only {' and '.join(MUTABLE_ON_RESUME)} may change")
    config = train_config(command, command.options)  # type: ignore[attr-defined]
    if saved is not None:                # not a flag: the saved run's (runs of the library may set it either way)
        config = dataclasses.replace(config, shared_context=saved.shared_context)
    return command, config, saved


def _train_or_resume(command: TrainCommand, config: TrainConfig, saved: TrainConfig | None) -> RunDirectory:
    """A new run, or (``--resume``) the saved run changed only by the given flags (a differing setting is an error
    naming its flag)."""
    if saved is None:
        return train(config, command.run_path, progress=True, backend=command.backend,
                     ray_address=command.ray_address)
    changes = _resume_changes(saved, config)
    return train(None, command.run_path, resume=True, changes=changes, labels={key: _flag(key) for key in changes},
                 progress=True, backend=command.backend, ray_address=command.ray_address)


def command_train(argv: Sequence[str]) -> None:
    command, config, saved = _parse_run(TrainCommand, argv, "rdmp-gym train")
    _setup(command)
    run = _train_or_resume(command, config, saved)
    last = run.read_log()[-1]
    print(f"{run.path}: {last['update']} updates, {last['episodes']} episodes, "
          f"best policy return {last['best_eval_return']:.4g}")
    if command.video:
        print(f"wrote {record_best_episode(run.path)}")


def command_evaluate(argv: Sequence[str]) -> None:
    command = parse_evaluate(argv)
    _setup(command)
    result = evaluate_run(command.run, command.episodes, workers=command.workers, policy=command.policy,
                          video=command.video, progress=True, backend=command.backend,
                          ray_address=command.ray_address)
    _print_comparison(result)
    print(f"wrote {Path(command.run) / 'evaluation.json'} and evaluation.png" +
          (f" and {result['video']}" if "video" in result else ""))


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
    return ", ".join(f"{cause} {len(found)} (context{'s' if len(found) > 1 else ''} "
                     f"{', '.join(map(str, found))})" for cause, found in failure_contexts(failures).items()) or "none"


def _write_imitation_figure(config: TrainConfig, out: Path) -> str:
    """``fit.png``: the demonstration against the env's own imitation DMP, the one training starts from."""
    env = config.task.make()
    try:
        dmp = env.unwrapped.dmp
    finally:
        env.close()
    demo = load_demonstration(config.demo or config.env_kwargs.get("style", 1))
    plot_fit(demo.t - demo.t[0], demo.Y, dmp.rollout(demo.t), out / "fit.png", title=f"{demo.name}: imitation")
    return demo.name


def command_main(argv: Sequence[str]) -> None:
    command, config, saved = _parse_run(MainCommand, argv, "rdmp-gym main")
    _setup(command)
    out = Path(command.out)
    out.mkdir(parents=True, exist_ok=True)
    print("[1/4] imitation: the env's rhythmic DMP fitted to the demonstration (the start of training)")
    print(f"      {_write_imitation_figure(config, out)} -> {out / 'fit.png'}")
    print(f"[2/4] the paper's figures (2, 6, 7, 8, 9, 12) for the built-in demonstrations -> {out / 'figures'}")
    write_paper_figures(out / "figures")
    print(f"[3/4] {config.agent}: {config.updates} updates x {config.rollouts} rollouts on random training contexts, "
          f"{config.workers} worker(s); policy checked on {config.eval_episodes} validation contexts every "
          f"{config.eval_every} updates")
    run = _train_or_resume(command, config, saved)
    curve = [(r["episodes"], r["eval_success"], r["eval_coverage"]) for r in run.read_log()
             if r.get("eval_coverage") is not None]
    print("held-out (validation) curve, episodes: success rate / coverage  " +
          "  ".join(f"{e}: {s:.2f}/{c:.3f}" for e, s, c in curve))
    print(f"[4/4] the final policy against the imitation on {command.episodes} test contexts (never trained on)")
    result = evaluate_run(run.path, command.episodes, workers=config.workers, policy="last", video=command.video,
                          progress=True)
    _print_comparison(result)
    summary = {"fit": str(out / "fit.png"), "figures": str(out / "figures"), "run": str(run.path),
               "learning_curve": str(run.curve_png), "validation_curve": curve,
               "evaluation": {name: {k: v for k, v in result[name].items()
                                     if k.endswith(("_mean", "_fraction", "_rate")) or k == "intervals"}
                              for name in ("imitation", "trained")}}
    (out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    print(f"wrote {out / 'summary.json'}, {out / 'fit.png'}, {run.curve_png}, {run.path / 'evaluation.png'}")


def _setup(command: Any) -> None:
    """Logging, the headless-video check and one torch thread per process (where torch is installed)."""
    logging.basicConfig(level=logging.INFO if command.verbose else logging.WARNING,
                        format="%(levelname)s %(name)s: %(message)s")
    if getattr(command, "video", False) and not os.environ.get("MUJOCO_GL") and not os.environ.get("DISPLAY"):
        raise ValueError("--video: no display; run with MUJOCO_GL=egl (or osmesa) set in the environment")
    if isinstance(command, (TrainCommand, EvaluateCommand)):
        try:
            import torch  # optional: only the torch learners need it
        except ModuleNotFoundError:
            return
        torch.set_num_threads(1)
