"""``rdmp-gym train``, ``evaluate`` and ``main`` (the job of ``make run``); they need the ``agents`` extra.

Every command's flags are derived with `tyro <https://brentyi.github.io/tyro/>`_ from typed dataclasses. The run's
flags are :class:`~rdmp_gym.agents.train_config.TrainConfig`'s fields, one flag per field with its type, default and
the first sentence of its documentation as help (``env_id`` is ``--env``, ``env_kwargs`` ``--env-option KEY VALUE``,
``reset_options`` ``--reset-option KEY VALUE``), and the chosen learner's settings are ``--options.NAME`` (the fields
of its settings class, e.g. :class:`~rdmp_gym.agents.learners.bbrl_config.BBRLConfig`)::

    rdmp-gym train --out runs/bbrl                      # the main job's learner (bbrl) on the current task
    rdmp-gym train --agent cpi2 --updates 30 --options.sigma 0.2 --out runs/cpi2
    rdmp-gym train --agent bbrl --options.sigma-factors approach 3 amplitude 2 --out runs/wide
    rdmp-gym train --env-option style 2 --env-option groups '["periodic", "amplitude"]' --out runs/style2
    rdmp-gym train --agent cmaes --env InvertedPendulum-v5 --env-option duration 1.0 --out runs/pendulum
    rdmp-gym train --out runs/bbrl --resume --updates 300       # continue (and extend) a run
    rdmp-gym evaluate runs/bbrl --episodes 20 --video   # final policy on the 20 test contexts
    rdmp-gym main --out runs/main

The env's settings come from the env itself (its defaults) or from ``--env-option KEY VALUE``: the flag may be
repeated and takes several pairs, a key given twice takes the last value, and a VALUE is read as JSON where it is
JSON (:func:`env_value`). A run saves its configuration as ``config.json``; ``--resume`` reads it back (its env
settings come back as env options) and applies only the flags given (``--updates`` and ``--workers`` may change,
any other differing setting is an error naming its flag). The launcher :mod:`rdmp_gym.agents.cli` calls
:func:`command_train`, :func:`command_evaluate` and :func:`command_main`.
"""

from __future__ import annotations

import atexit
import dataclasses
import inspect
import json
import logging
import os
import re
import shutil
import tempfile
import typing
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
import tyro
from rdmp_gym.envs.specs import is_episodic

from rdmp_gym.figures.paper import write_paper_figures

from .config import Settings
from .imitation import load_demonstration
from .plots import logged_metrics, plot_fit
from .protocol import interval
from .report import compared_quantities, evaluate_run, record_best_episode
from .runs import RunDirectory
from .tasks import TaskSpec, failure_contexts, main_agent, main_env_kwargs, main_options
from .train_config import TrainConfig
from .training import MUTABLE_ON_RESUME, load_run_config, train

__all__ = ["RUN_FIELDS", "EvaluateCommand", "MainCommand", "TrainCommand", "command_evaluate", "command_main",
           "command_train", "env_value", "parse_evaluate", "parse_main", "parse_train", "train_config"]

logger = logging.getLogger(__name__)

_WORKERS = os.cpu_count() or 1
#: the run's settings given by flags: every field of :class:`TrainConfig` but the learner's settings, whose fields
#: are ``--options.NAME`` flags of their own
RUN_FIELDS = tuple(item.name for item in dataclasses.fields(TrainConfig) if item.name != "options")
#: the flags of the fields that are not ``--NAME`` (their key-value fields: ``--env-option KEY VALUE``)
_FLAG_NAMES = {"env_id": "env", "env_kwargs": "env-option", "reset_options": "reset-option"}
#: the fields given as KEY VALUE pairs, and their help (the pairs' form is the command line's, not the config's)
_PAIRS = {
    "env_kwargs": "the env's settings over its own defaults, KEY VALUE pairs (repeatable; a key given twice: the last "
                  "value). VALUE is JSON where it parses (2, 0.5, true, null, '[\"periodic\", \"amplitude\"]'), "
                  "else text. A step-based env also takes the black-box wrapper's settings (p_gains, duration, ...); "
                  "the main job's env gets cup_clearance 0.01 unless given (null: no clearance)",
    "reset_options": "options for every reset, KEY VALUE pairs read as --env-option reads them (e.g. to fix the "
                     "context)",
}
_PYTHON_WORDS: dict[str, Any] = {"None": None, "True": True, "False": False}


def env_value(text: str) -> Any:
    """The value of an ``--env-option``/``--reset-option`` VALUE: JSON where ``text`` parses as JSON (numbers,
    ``true``/``false``/``null``, lists such as ``["periodic", "amplitude"]``, objects), ``None``/``True``/``False`` as
    in Python, else ``text`` itself (a JSON string, ``'"2"'``, keeps a number-like text a text)."""
    if text in _PYTHON_WORDS:
        return _PYTHON_WORDS[text]
    try:
        return json.loads(text)
    except json.JSONDecodeError:
        return text


def _attribute_help(kind: type) -> dict[str, str]:
    """``{attribute: help}``: the first sentence of each entry of the ``Attributes:`` section of ``kind``'s docstring,
    its reStructuredText markup removed."""
    doc = inspect.cleandoc(kind.__doc__ or "")
    entries: dict[str, str] = {}
    name = None
    for line in doc.partition("\nAttributes:\n")[2].splitlines():
        entry = re.match(r"    (\w+): (.*)", line)
        if entry:
            name, entries[entry[1]] = entry[1], entry[2]
        elif name and line.startswith("        "):
            entries[name] += " " + line.strip()
    plain = {key: re.sub(r":\w+:`~?(?:[\w.]*\.)?(\w+)`", r"\1", text).replace("``", "")
             for key, text in entries.items()}
    return {key: re.split(r"(?<!e\.g)(?<!i\.e)\.(?:\s|$)", text, maxsplit=1)[0] for key, text in plain.items()}


def _run_flags(name: str, **defaults: Any) -> type:
    """The run's flags as a tyro dataclass ``name``: one field per :data:`RUN_FIELDS` entry, with :class:`TrainConfig`'s
    type and default (``defaults`` replace some) and the first sentence of its documentation as help; the key-value
    fields are text pairs (``dict[str, str]``, read by :func:`env_value`)."""
    hints = typing.get_type_hints(TrainConfig)
    helps = _attribute_help(TrainConfig)
    specs = []
    for item in dataclasses.fields(TrainConfig):
        if item.name not in RUN_FIELDS:
            continue
        flag = _FLAG_NAMES.get(item.name)
        if item.name in _PAIRS:
            arg = tyro.conf.arg(name=flag, metavar="KEY VALUE", help=_PAIRS[item.name])
            specs.append((item.name, Annotated[dict[str, str], arg], field(default_factory=dict)))
        else:
            arg = tyro.conf.arg(name=flag, help=helps[item.name])
            specs.append((item.name, Annotated[hints[item.name], arg],
                          field(default=defaults.get(item.name, item.default))))
    flags = dataclasses.make_dataclass(name, specs)
    flags.__module__ = __name__
    return flags


@dataclass
class _CommandFlags:
    """The flags of ``train`` and ``main`` beside the run's."""

    time_column: str = "t"
    """name of the --demo CSV's time column (seconds)"""
    rate: float | None = None
    """resample --demo onto an even grid at this rate in Hz (default: keep the samples, evenly spaced)"""
    backend: Literal["local", "ray"] = "local"
    """where the episodes run: local worker processes or Ray actors (the numbers are the same)"""
    ray_address: str | None = None
    """Ray cluster to join with --backend ray (default: $RAY_ADDRESS, else a new local Ray instance)"""
    resume: bool = False
    """continue the run in --out from its checkpoint with its own config.json (flags only to change it)"""
    video: bool = False
    """record the best policy's episode (best_episode.mp4); checked before any work: the env must record episodes"""
    verbose: bool = False
    """log progress details"""


@dataclass
class TrainCommand(_CommandFlags, _run_flags("TrainRun", workers=_WORKERS)):
    """Train an agent: bbrl with the main job's settings on the current task, cmaes on a step-based env."""

    out: str = ""
    """run directory (required)"""

    @property
    def run_path(self) -> Path:
        """The run directory the command trains (and ``--resume`` continues)."""
        return Path(self.out)


@dataclass
class MainCommand(_CommandFlags, _run_flags("MainRun", workers=_WORKERS, updates=200, eval_episodes=8,
                                            eval_every=20)):
    """Imitation, the paper's figures, contextual refinement and evaluation on test contexts, end to end."""

    out: str = "runs/main"
    """output directory"""
    episodes: int = 20
    """test contexts"""

    @property
    def run_path(self) -> Path:
        """The run directory: ``train`` in the output directory."""
        return Path(self.out) / "train"


#: a ``train`` or ``main`` command
RunCommand = TrainCommand | MainCommand


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
    """record the best episode (best_episode.mp4); checked before the evaluation: the env must record episodes"""
    verbose: bool = False
    """log progress details"""


def _prepare_demo(command: RunCommand) -> str:
    """``--demo``, or with ``--time-column``/``--rate`` an even-grid copy of it in a temporary folder (removed at
    exit); the run copies it in as ``demo.npz``, so it holds the demonstration it was trained on."""
    if not command.demo or (command.time_column == "t" and command.rate is None):
        return command.demo
    demo = load_demonstration(command.demo, time_column=command.time_column, rate=command.rate)
    folder = Path(tempfile.mkdtemp(prefix="rdmp-gym-demo-"))
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    demo.to_npz(folder / "demo.npz")
    return str(folder / "demo.npz")


def train_config(command: RunCommand, options: Settings | None = None) -> TrainConfig:
    """The training run of a ``train``/``main`` command: its :data:`RUN_FIELDS` as they are (``env_kwargs`` as the
    command holds them: :func:`parse_train` puts the main job's keywords under the given ones on a new run), the
    demonstration prepared (:func:`_prepare_demo`); ``options``: the learner's settings (default: the task's defaults
    for the agent, the main job's options for its learner)."""
    values = {name: getattr(command, name) for name in RUN_FIELDS}
    values.update(env_kwargs=dict(command.env_kwargs), reset_options=dict(command.reset_options) or None,
                  demo=_prepare_demo(command))
    if options is None:
        options = _default_options(command.agent, command.env_id, values["env_kwargs"])
    return TrainConfig(**values, options=options)


def _default_options(agent: str | None, env_id: str, env_kwargs: dict[str, Any]) -> Settings:
    """The learner's settings of a new run: the task's defaults for the agent (None: the env's default learner; the
    main job's for its learner)."""
    agent = agent or main_agent(env_id)
    return TrainConfig(agent=agent, env_id=env_id, env_kwargs=env_kwargs, options=main_options(agent, env_id)).options


def _saved_command(kind: type[RunCommand], saved: TrainConfig, out: str) -> RunCommand:
    """The command whose flags rebuild ``saved`` (a resumed run's defaults, so that only given flags change it; its
    env settings come back as env options)."""
    values = {name: getattr(saved, name) for name in RUN_FIELDS}
    values.update(env_kwargs=dict(saved.env_kwargs), reset_options=dict(saved.reset_options or {}))
    return kind(**values, out=out, resume=True)


def _gather_pairs(argv: list[str], flag: str) -> tuple[list[str], dict[str, Any]]:
    """``argv`` without the ``flag KEY VALUE ...`` groups, and their pairs (``{key: env_value(VALUE)}``): a repeated
    flag adds its pairs, a key given twice keeps its last value."""
    names = (flag, "--" + flag[2:].replace("-", "_"))
    rest: list[str] = []
    pairs: dict[str, Any] = {}
    index = 0
    while index < len(argv):
        if argv[index] not in names:
            rest.append(argv[index])
            index += 1
            continue
        end = index + 1
        while end < len(argv) and not argv[end].startswith("--"):
            end += 1
        values = argv[index + 1:end]
        if not values or len(values) % 2:
            raise ValueError(f"{flag}: expected KEY VALUE pairs, got {' '.join(values) or 'none'!r}")
        pairs.update({key: env_value(value) for key, value in zip(values[::2], values[1::2], strict=True)})
        index = end
    return rest, pairs


def _refuse_unknown(unknown: Sequence[str], prog: str) -> None:
    """A flag the command does not have (the learner's ``--options.NAME`` are read later) is a ValueError that says how
    a setting of the env is given instead."""
    for token in unknown:
        if token.startswith("--") and not token.startswith("--options.") and token != "--help":
            key = token[2:].partition("=")[0].replace("-", "_")
            raise ValueError(f"{token}: {prog} has no such flag ({prog} --help lists them); a setting of the env is "
                             f"given as --env-option {key} VALUE (a JSON value where it is one, e.g. --env-option "
                             f"groups '[\"periodic\", \"amplitude\"]')")


def _parse_flags(kind: type[RunCommand], argv: Sequence[str], prog: str, *, read_run: bool = True
                 ) -> tuple[RunCommand, TrainConfig | None]:
    """Parse a ``train``/``main`` command line into the command, with the learner's settings as ``options``, and
    (for ``--resume`` with ``read_run``) the saved run it continues.

    The ``--env-option``/``--reset-option`` pairs are gathered first (:func:`_gather_pairs`). The agent (and for
    ``--resume`` the saved run) decides which learner settings exist, so a first pass reads the run's flags and a
    second parses everything, the learner's ``--options.NAME`` flags included, with the defaults of the task (or of
    the saved run). Dict settings (``sigma_factors``) and the env options add to the defaults'. Without ``read_run``
    a ``--resume`` line is parsed over the task's defaults (no run directory is read).
    """
    argv, env_pairs = _gather_pairs(list(argv), "--env-option")
    argv, reset_pairs = _gather_pairs(argv, "--reset-option")
    first, unknown = tyro.cli(kind, args=argv, prog=prog, add_help=False, return_unknown_args=True)
    _refuse_unknown(unknown, prog)
    read_run = read_run and first.resume
    if read_run and not first.out:
        raise ValueError("--out: the run directory is required")
    saved = load_run_config(RunDirectory(first.run_path)) if read_run else None
    defaults = _saved_command(kind, saved, first.out) if saved is not None else \
        dataclasses.replace(first, env_kwargs=main_env_kwargs(first.env_id))
    env_kwargs = {**defaults.env_kwargs, **env_pairs}
    reset_options = {**defaults.reset_options, **reset_pairs}
    options = saved.options if saved is not None else _default_options(first.agent, first.env_id, env_kwargs)
    dicts = {item.name: getattr(options, item.name) for item in dataclasses.fields(options)
             if isinstance(getattr(options, item.name), dict)}
    flags = dataclasses.make_dataclass(kind.__name__, [("options", type(options), field(default=None))],
                                       bases=(kind,))
    flags.__module__ = kind.__module__
    values = {item.name: getattr(defaults, item.name) for item in dataclasses.fields(kind)}
    start = flags(**{**values, "env_kwargs": {}, "reset_options": {}},      # tyro fixes the keys of a given dict
                  options=dataclasses.replace(options, **{key: {} for key in dicts}))
    parsed = tyro.cli(flags, args=argv, prog=prog, default=start, description=kind.__doc__)
    given = dataclasses.replace(parsed.options, **{name: {**value, **getattr(parsed.options, name)}
                                                   for name, value in dicts.items()})
    command = flags(**{**{item.name: getattr(parsed, item.name) for item in dataclasses.fields(kind)},
                       "env_kwargs": env_kwargs, "reset_options": reset_options}, options=given)
    if not command.out:
        raise ValueError("--out: the run directory is required")
    return command, saved


def parse_train(argv: Sequence[str]) -> TrainCommand:
    """The ``train`` command line parsed into its :class:`TrainCommand` (the learner's settings as ``options``, the
    env options gathered and read by :func:`env_value`), without running it or reading a run directory (a
    ``--resume`` line is parsed over the task's defaults)."""
    return _parse_flags(TrainCommand, argv, "rdmp-gym train", read_run=False)[0]  # type: ignore[return-value]


def parse_main(argv: Sequence[str]) -> MainCommand:
    """The ``main`` command line parsed into its :class:`MainCommand`, without running it (see :func:`parse_train`)."""
    return _parse_flags(MainCommand, argv, "rdmp-gym main", read_run=False)[0]  # type: ignore[return-value]


def parse_evaluate(argv: Sequence[str]) -> EvaluateCommand:
    """The ``evaluate`` command line parsed into its :class:`EvaluateCommand`, without running it."""
    return tyro.cli(EvaluateCommand, args=argv, prog="rdmp-gym evaluate")


def _flag(key: str) -> str:
    """The command-line flag of a setting of the run (``key``: a field, or ``field.entry`` of a dict field)."""
    name, _, entry = key.partition(".")
    if name == "options":
        return "--options." + entry.replace("_", "-")
    flag = "--" + _FLAG_NAMES.get(name, name.replace("_", "-"))
    return f"{flag} {entry}" if entry else flag


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


def _parse_run(kind: type[RunCommand], argv: Sequence[str], prog: str
               ) -> tuple[RunCommand, TrainConfig, TrainConfig | None]:
    """A ``train``/``main`` command line: the command, its training run and (``--resume``) the saved run."""
    command, saved = _parse_flags(kind, argv, prog)
    if saved is not None and command.agent != saved.agent:      # the run's learner settings are its agent's
        raise ValueError(f"--agent: {command.agent!r} differs from the run's {saved.agent!r} "
                         f"({RunDirectory(command.run_path).config_path}); a resumed run keeps its configuration, "
                         f"only {' and '.join(MUTABLE_ON_RESUME)} may change")
    return command, train_config(command, command.options), saved  # type: ignore[attr-defined]


def _with_flag_hint(error: ValueError) -> str:
    """``error``'s message, and where its reason (the black-box wrapper's) names a setting of the wrapper, the flag
    that sets it (``--env-option NAME VALUE``)."""
    from rdmp_gym.envs.blackbox import WRAPPER_SETTINGS

    name = str(error.__cause__ or error).partition(":")[0].strip()
    if name in WRAPPER_SETTINGS:
        return f"{error} (set it with --env-option {name} VALUE)"
    return str(error)


def _check_recording(env: Any, env_id: str) -> None:
    """``--video``: ValueError unless the env records episodes (``record_episode``, and ``can_record()`` where the env
    has that cheap check) and MuJoCo renders here."""
    base = env.unwrapped
    if not callable(getattr(base, "record_episode", None)):
        raise ValueError(f"--video: {env_id} cannot record an episode ({type(base).__name__} has no "
                         f"record_episode); leave out --video")
    can_record = getattr(base, "can_record", None)
    if callable(can_record) and not can_record():
        raise ValueError(f"--video: {env_id} cannot record an episode here (its env renders no RGB frames: "
                         f"render_mode {getattr(base, 'render_mode', None)!r}); leave out --video")
    import mujoco

    try:
        mujoco.Renderer(mujoco.MjModel.from_xml_string("<mujoco/>"), 8, 8).close()
    except Exception as error:          # each OpenGL backend fails in its own way
        raise ValueError(f"--video: MuJoCo cannot render here ({error}); set MUJOCO_GL=egl (or osmesa) in the "
                         f"environment, or leave out --video") from None


def _check_task(task: TaskSpec, video: bool) -> None:
    """Build the run's env once, before any work, where that can fail for a reason a flag fixes: a step-based env the
    black-box wrapper cannot drive (the error names the ``--env-option`` to give) and, with ``video``, an env that
    cannot record its episodes."""
    if not video and is_episodic(task.env_id):
        return
    try:
        env = task.make()
    except ValueError as error:
        raise ValueError(_with_flag_hint(error)) from error
    try:
        if video:
            _check_recording(env, task.env_id)
    finally:
        env.close()


def _train_or_resume(command: RunCommand, config: TrainConfig, saved: TrainConfig | None) -> RunDirectory:
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
    _setup(command, config.task)
    run = _train_or_resume(command, config, saved)
    last = run.read_log()[-1]
    print(f"{run.path}: {last['update']} updates, {last['episodes']} episodes, "
          f"best policy return {last['best_eval_return']:.4g}")
    if command.video:
        print(f"wrote {record_best_episode(run.path)}")


def command_evaluate(argv: Sequence[str]) -> None:
    command = parse_evaluate(argv)
    _setup(command, load_run_config(RunDirectory(command.run)).task if command.video else None)
    result = evaluate_run(command.run, command.episodes, workers=command.workers, policy=command.policy,
                          video=command.video, progress=True, backend=command.backend,
                          ray_address=command.ray_address)
    _print_comparison(result)
    figure = " and evaluation.png" if (Path(command.run) / "evaluation.png").is_file() else ""
    print(f"wrote {Path(command.run) / 'evaluation.json'}{figure}" +
          (f" and {result['video']}" if "video" in result else ""))


def _interval_text(summary: dict[str, Any], key: str) -> str:
    """``"mean [low, high]"`` of the interval ``key`` of a policy's summary, ``"-"`` where it has none."""
    found = summary["intervals"].get(key)
    return "-" if found is None else f"{found['estimate']:.3f} [{found['low']:.3f}, {found['high']:.3f}]"


#: the per-context list of an evaluation's interval key (the task's metrics: their own keys)
_PER_CONTEXT = {"return": "returns"}


def _paired_gain(result: dict[str, Any], key: str) -> str:
    """The trained policy's mean gain over the imitation in ``key`` on the same test contexts, with its 95 %
    interval; ``"-"`` where a context has no value of it."""
    name = _PER_CONTEXT.get(key, key)
    gain = (np.array(result["trained"][name], dtype=float) - np.array(result["imitation"][name], dtype=float))
    return str(interval(gain, "mean")) if gain.size and np.all(np.isfinite(gain)) else "-"


def _print_comparison(result: dict[str, Any]) -> None:
    """Imitation vs trained on the test contexts: the return, the success rate (where the env reports success), the
    task's metrics by their labels and the path smoothness, means with 95 % bootstrap intervals over the contexts,
    and the trained policy's paired gains over the imitation."""
    columns = compared_quantities(result)
    width = max(22, *(len(label) for _, label in columns))
    print(f"{'policy':>10} " + " ".join(f"{label:>{width}}" for _, label in columns))
    for name in ("imitation", "trained"):
        print(f"{name:>10} " + " ".join(f"{_interval_text(result[name], key):>{width}}" for key, _ in columns))
    gains = ", ".join(f"{label} {_paired_gain(result, key)}" for key, label in columns if key != "jerk_ratio")
    print(f"paired gain over the imitation on the same {len(result['trained']['returns'])} test contexts (mean, "
          f"95 % CI): {gains}")
    for name in ("imitation", "trained"):
        if result[name].get("failures") is not None:
            print(f"{name} fails on: {_failure_text(result[name]['failures'])}")


def _failure_text(failures: list[str]) -> str:
    """Each missed success criterion and where it was missed (e.g. the wiping task's ``"cup 2 (contexts 3, 7),
    coverage 1 (context 3)"``)."""
    return ", ".join(f"{cause} {len(found)} (context{'s' if len(found) > 1 else ''} "
                     f"{', '.join(map(str, found))})" for cause, found in failure_contexts(failures).items()) or "none"


def _validation_curve(records: list[dict[str, Any]]) -> tuple[list[tuple], list[str]]:
    """The policy's numbers on the validation contexts wherever it was evaluated, ``(episodes, return, success rate,
    the task's metrics...)`` (no success rate where the env reports none), and the names of those numbers."""
    evaluated = [r for r in records if r.get("eval_return_mean") is not None]
    keys = ["eval_return_mean", *(["eval_success"] if any(r.get("eval_success") is not None for r in evaluated)
                                  else []), *(f"eval_{key}" for key, _ in logged_metrics(evaluated))]
    names = ["return", *(["success rate"] if "eval_success" in keys else []),
             *(label for _, label in logged_metrics(evaluated))]
    return [(r["episodes"], *(r.get(key) for key in keys)) for r in evaluated], names


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
    _setup(command, config.task)
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
    curve, names = _validation_curve(run.read_log())
    print(f"held-out (validation) curve, episodes: {' / '.join(names)}  " +
          "  ".join(f"{row[0]}: " + "/".join("-" if v is None else f"{v:.3g}" for v in row[1:]) for row in curve))
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


def _setup(command: Any, task: TaskSpec | None) -> None:
    """Logging, the checks of ``task`` before any work (:func:`_check_task`; None: none) and one torch thread per
    process (where torch is installed; imported after the checks, so that a refusal is quick)."""
    logging.basicConfig(level=logging.INFO if command.verbose else logging.WARNING,
                        format="%(levelname)s %(name)s: %(message)s")
    if task is not None:
        _check_task(task, command.video)
    try:
        import torch  # optional: only the torch learners need it
    except ModuleNotFoundError:
        return
    torch.set_num_threads(1)
