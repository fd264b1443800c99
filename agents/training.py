"""Training runs: one loop for every agent, which runs the updates and calls the callbacks around them.

An agent does one update per call of ``train_update`` (``rollouts`` training episodes) and maps
context observations to actions with ``policy_actions``. :class:`ESAgent` wraps the ask/tell learners
(PI², CMA-ES, the contextual learners); ``rdmp_gym.agents.sb3.PPOAgent`` wraps stable-baselines3 PPO.

Seeds: the run seed makes a ``SeedSequence`` whose children drive the learner, the training episodes'
reset seeds (drawn from ``[0, 2**30)``), the perturbed start and the contexts that standardise a
contextual learner's features; the same config gives the same log. What happens around the updates (the
policy's evaluation on the first ``eval_episodes`` validation contexts of :mod:`rdmp_gym.agents.protocol`, which
no training episode uses, the best policy chosen there and never on the test contexts, the log, the checkpoint)
is done by callbacks (:mod:`rdmp_gym.agents.callbacks`).
"""

from __future__ import annotations

import logging
import platform
import subprocess
import time
from collections.abc import Iterable, Mapping
from dataclasses import replace
from datetime import datetime, timezone
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np

from .callbacks import Callback, TrainingState, default_callbacks, merge_callbacks
from .errors import NoValidEpisodesError
from .imitation import load_demonstration
from .learners import EpisodeBatch, Learner, SearchSpace, make_learner
from .plots import plot_learning_curve
from .pool import Evaluator
from .protocol import TRAIN_SEED_LIMIT, context_observations, stratified_validation_seeds, validation_seeds
from .registry import agent_spec
from .runs import RunDirectory, sha256_file, write_atomic
from .train_config import AGENTS, Agent, TrainConfig

__all__ = ["AGENTS", "ESAgent", "NoValidEpisodesError", "TrainConfig", "environment_record", "load_run_config",
           "train"]

logger = logging.getLogger(__name__)

_FEATURE_CONTEXTS = 64   # training contexts whose mean and spread standardise a contextual learner's features


class ESAgent:
    """An ask/tell learner plus the episodes it runs: one update = ask, evaluate, tell.

    Args:
        learner: the learner.
        evaluator: runs the episodes.
        episode_rng: draws the reset seeds of the training episodes.
        shared_context: one reset seed per update (all rollouts see the same context).
    """

    def __init__(self, learner: Learner, evaluator: Evaluator, episode_rng: np.random.Generator,
                 shared_context: bool) -> None:
        self.learner, self.evaluator, self.episode_rng = learner, evaluator, episode_rng
        self.shared_context = shared_context

    @property
    def exploration(self) -> float:
        return self.learner.exploration

    def train_update(self) -> EpisodeBatch:
        rollouts = self.learner.rollouts
        count = 1 if self.shared_context and not self.learner.uses_context else rollouts
        seeds = np.broadcast_to(self.episode_rng.integers(TRAIN_SEED_LIMIT, size=count), (rollouts,)).copy()
        observations = None
        if self.learner.uses_context:
            seeds = self.learner.choose_seeds(seeds)
            observations = context_observations(self.evaluator.env, seeds, self.evaluator.spec.options())
        actions = self.learner.ask(observations)
        batch = self.evaluator.run(actions, seeds)
        self.learner.tell(batch)
        return batch

    def policy_actions(self, observations: np.ndarray) -> np.ndarray:
        return self.learner.policy_actions(observations)

    def state_dict(self) -> dict[str, Any]:
        return {"learner": self.learner.state_dict(), "episode_rng": self.episode_rng.bit_generator.state}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        self.learner.load_state_dict(state["learner"])
        self.episode_rng.bit_generator.state = state["episode_rng"]

    def close(self) -> None:
        return None


def _seed_streams(seed: int) -> dict[str, np.random.Generator]:
    names = ("learner", "episodes", "start", "features")
    children = np.random.SeedSequence(seed).spawn(len(names))
    return {name: np.random.default_rng(child) for name, child in zip(names, children, strict=True)}


def _theta_slices(base: Any) -> dict[str, slice]:
    """``{group: slice}`` of the env's parameters ``theta``: its own where it names them (the black-box wrapper, whose
    ``tempo`` is no DMP group), else its DMP's for its groups."""
    if hasattr(base, "param_slices"):
        return dict(base.param_slices())
    return base.dmp.param_slices(base.groups)


def _initial_action(config: TrainConfig, evaluator: Evaluator, rng: np.random.Generator) -> np.ndarray:
    """``[n]`` the start (see ``TrainConfig.start``), clipped to the action box."""
    action = np.zeros(evaluator.n_actions)
    if config.start == "perturbed":
        action = config.perturbation * rng.standard_normal(action.size)
    elif config.start == "shrunk":
        base = evaluator.env.unwrapped
        theta = base.action_to_params(action)
        for name, part in _theta_slices(base).items():
            if not name.startswith("initial") and name != "tempo":
                theta[part] *= 1.0 - config.perturbation
        action = np.asarray(base.params_to_action(theta), dtype=np.float64)
    clipped = float(np.mean(np.abs(action) > 1.0))
    if clipped:
        logger.info("start: %.0f%% of the start action lies outside [-1, 1] and is clipped", 100 * clipped)
    return np.clip(action, -1.0, 1.0)


def _make_agent(config: TrainConfig, evaluator: Evaluator, streams: dict[str, np.random.Generator],
                initial: np.ndarray, run_path: Path) -> Agent:
    spec = agent_spec(config.agent)
    if spec.kind == "sb3":
        return spec.load().from_run(config, initial, run_path)
    base = evaluator.env.unwrapped
    weights = base.action_time_weights() if config.agent == "pi2" else None
    space = None
    if spec.uses_context or getattr(config.options, "length", 0.0) > 0:
        seeds = streams["features"].integers(TRAIN_SEED_LIMIT, size=_FEATURE_CONTEXTS)
        space = SearchSpace.from_env(evaluator.env, context_observations(evaluator.env, seeds, config.task.options()))
    learner = make_learner(config.agent, initial, config.rollouts, streams["learner"], config.options, weights,
                           space)
    return ESAgent(learner, evaluator, streams["episodes"], config.shared_context)


MUTABLE_ON_RESUME = ("updates", "workers")
_PACKAGES = ("rdmp-gym", "numpy", "scipy", "gymnasium", "mujoco", "cma", "stable-baselines3", "torch", "filelock")


def _git_commit() -> dict[str, Any]:
    """The commit (and whether the work tree differs) of the checkout rdmp-gym runs from, if it is one."""
    source = Path(__file__).resolve().parent.parent
    if not any((folder / ".git").exists() for folder in (source, *source.parents)):
        return {"commit": None}
    try:
        commit = subprocess.run(["git", "-C", str(source), "rev-parse", "HEAD"], capture_output=True, text=True,
                                timeout=10, check=True).stdout.strip()
        status = subprocess.run(["git", "-C", str(source), "status", "--porcelain", "--untracked-files=no"],
                                capture_output=True, text=True, timeout=10, check=True).stdout
    except (OSError, subprocess.SubprocessError):
        return {"commit": None}
    return {"commit": commit, "dirty": bool(status.strip())}


def environment_record() -> dict[str, Any]:
    """Versions of Python and the packages a run depends on, rdmp-gym's version and git commit."""
    versions: dict[str, str | None] = {}
    for name in _PACKAGES:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = None
    return {"time": datetime.now(timezone.utc).isoformat(timespec="seconds"),
            "python": platform.python_version(), "packages": versions, "rdmp_gym": _git_commit()}


def load_run_config(run: RunDirectory | str | Path) -> TrainConfig:
    """The configuration of a run directory, with its demonstration resolved to the run's own copy.

    A relative ``demo`` is relative to the run directory; a copy that no longer matches the sha256 in
    ``provenance.json`` is a ``ValueError``.
    """
    run = run if isinstance(run, RunDirectory) else RunDirectory(run)
    try:
        config = TrainConfig.from_dict(run.read_config())
    except (TypeError, ValueError) as error:
        raise type(error)(f"{run.config_path}: {error}; restore the file or start a new run") from error
    if not config.demo:
        return config
    demo = Path(config.demo) if Path(config.demo).is_absolute() else run.path.resolve() / config.demo
    if not demo.exists():
        raise FileNotFoundError(f"demo: {demo} (named by {run.config_path}) is missing")
    expected = run.read_provenance().get("demo", {}).get("sha256")
    if expected is not None and sha256_file(demo) != expected:
        raise ValueError(f"demo: {demo} changed since the run started (sha256 differs from provenance.json); "
                         "restore it or start a new run")
    return replace(config, demo=str(demo))


def _lookup(config: dict[str, Any], key: str) -> Any:
    field_name, _, entry = key.partition(".")
    value = config[field_name]
    return value if not entry else (value or {}).get(entry)


def _resumed_config(run: RunDirectory, config: TrainConfig | None, changes: Mapping[str, Any],
                    labels: Mapping[str, str]) -> TrainConfig:
    """The run's own configuration with ``changes`` applied (see :func:`train`)."""
    saved = load_run_config(run)
    given = dict(config.to_dict()) if config is not None else {}
    given.update(changes)
    fields = saved.to_dict()
    resolved = {}
    for key, value in given.items():
        label = labels.get(key, key)
        if key.partition(".")[0] not in fields:
            raise ValueError(f"{label}: not a setting of a run")
        if key in MUTABLE_ON_RESUME:
            resolved[key] = value
            continue
        current = _lookup(fields, key)
        if key == "demo" and value and current:
            if not Path(value).exists():
                raise FileNotFoundError(f"demo: {value} does not exist")
            same = sha256_file(Path(value)) == sha256_file(Path(current))
        else:
            same = value == current
        if not same:
            raise ValueError(f"{label}: {value!r} differs from the run's {current!r} ({run.config_path}); a resumed "
                             f"run keeps its configuration, only {' and '.join(MUTABLE_ON_RESUME)} may change")
    return replace(saved, **resolved)


def _start_files(run: RunDirectory, config: TrainConfig) -> TrainConfig:
    """Copy the demonstration into the new run; the config as stored (demo relative to the run)."""
    record = environment_record()
    provenance: dict[str, Any] = {"sessions": [{"started": "new", **record}]}
    stored = config
    if config.demo:
        source = Path(config.demo).resolve()
        load_demonstration(str(source))                  # a clear error for a missing or broken file
        copy = run.path / f"demo{source.suffix.lower()}"
        write_atomic(copy, source.read_bytes())
        provenance["demo"] = {"source": str(source), "copy": copy.name, "sha256": sha256_file(copy)}
        stored = replace(config, demo=copy.name)
    run.write_provenance(provenance)
    return stored


def _resume_session(run: RunDirectory, config: TrainConfig) -> None:
    """Record the changed ``updates``/``workers`` in ``config.json`` and this resume in ``provenance.json``;
    warn when the package versions changed."""
    stored = run.read_config()
    if any(stored.get(key) != getattr(config, key) for key in MUTABLE_ON_RESUME):
        run.write_config({**stored, **{key: getattr(config, key) for key in MUTABLE_ON_RESUME}})
    provenance = run.read_provenance()
    record = environment_record()
    sessions = provenance["sessions"]
    if sessions and isinstance(sessions[0], dict) and sessions[0].get("packages") != record["packages"]:
        before = sessions[0].get("packages") or {}
        changed = {k: (before.get(k), v) for k, v in record["packages"].items() if before.get(k) != v}
        logger.warning("%s: resuming with other package versions than the run started with: %s", run.path, changed)
    sessions.append({"started": "resume", **record})
    run.write_provenance(provenance)


def train(config: TrainConfig | None, out: str | Path, *, resume: bool = False,
          changes: Mapping[str, Any] | None = None, labels: Mapping[str, str] | None = None,
          progress: bool = False, backend: str = "local", ray_address: str | None = None,
          callbacks: Iterable[Callback] | None = None) -> RunDirectory:
    """Train an agent and write the run directory ``out`` (see :mod:`rdmp_gym.agents.runs`).

    Args:
        config: the run; with ``resume`` it may be None (use the run's ``config.json``), or must agree
            with it except in ``updates`` and ``workers``.
        out: run directory (a new run needs a new or empty one; it is locked while the run is written).
        resume: continue from the run's last checkpoint.
        changes: with ``resume``: settings to change (``field`` or ``field.key`` for an entry of
            ``env_kwargs``, ``options``, ``reset_options``); ``updates`` (to extend the run) and
            ``workers`` may change, any other value that differs from the run's is a ``ValueError``.
        labels: names for ``changes`` keys in error messages (e.g. the command-line flags).
        progress: show a progress bar.
        backend, ray_address: where the episodes run (see :class:`Evaluator`); the numbers do not depend on it.
        callbacks: run after the default set (:func:`~rdmp_gym.agents.callbacks.default_callbacks`: evaluation,
            best policy, log, checkpoint, first-update guard, progress bar); one that is an instance of a
            default's class takes that default's place (see :mod:`rdmp_gym.agents.callbacks`).
    Returns:
        the run directory.
    """
    run = RunDirectory(out)
    if not resume and (config is None or changes):
        raise ValueError("config: a new run needs a config (and no changes)")
    chosen = merge_callbacks(default_callbacks(progress), callbacks)
    with run.open(new=not resume):
        config = _resumed_config(run, config, changes or {}, labels or {}) if resume \
            else replace(config, demo=str(Path(config.demo).resolve()) if config.demo else "")
        streams = _seed_streams(config.seed)
        with Evaluator(config.task, config.workers, backend, ray_address) as evaluator:
            initial = _initial_action(config, evaluator, streams["start"])
            seeds = stratified_validation_seeds(evaluator.env, config.eval_episodes, config.task.options()) \
                if config.stratified_validation else validation_seeds(config.eval_episodes)
            observations = np.stack([evaluator.env.reset(seed=int(s), options=config.task.options())[0]
                                     for s in seeds])
            agent = _make_agent(config, evaluator, streams, initial, run.path)
            try:
                if resume:
                    _resume_session(run, config)
                else:
                    run.write_config(_start_files(run, config).to_dict())
                state = TrainingState(config, run, agent, evaluator, seeds, observations)
                fresh = _restore(state) if resume else True
                _run_updates(state, chosen, fresh)
            finally:
                agent.close()
        plot_learning_curve(run.read_log(), run.curve_png, title=f"{config.agent} on {config.env_id}")
    return run


def _run_updates(state: TrainingState, callbacks: Callback, fresh: bool) -> None:
    """The training loop: updates until ``config.updates`` or until a callback stops it, the callbacks called
    at their points (``fresh``: a new run, whose start is update 0)."""
    callbacks.on_training_start(state)
    try:
        if fresh:
            _after_update(state, callbacks, None)
        while state.update < state.config.updates and not state.stopped:
            batch = state.agent.train_update()
            state.update += 1
            state.episodes += batch.size
            _after_update(state, callbacks, batch)
    finally:
        callbacks.on_training_end(state)


def _after_update(state: TrainingState, callbacks: Callback, batch: EpisodeBatch | None) -> None:
    state.batch, state.record, state.evaluation = batch, {}, None
    if callbacks.on_update(state) is False and state.update < state.config.updates:
        state.stopped = True
        logger.info("training: stopped by a callback after update %d of %d", state.update, state.config.updates)


def _restore(state: TrainingState) -> bool:
    """Load a resumed run's checkpoint (validated) into ``state``; whether the run starts fresh (none yet)."""
    run, config = state.run, state.config
    checkpoint = run.load_checkpoint()
    if checkpoint is None:
        run.truncate_log(-1)   # killed before its first checkpoint: start over
        return True
    where = f"{run.checkpoint_path}"         # its fields' types are checked by load_checkpoint
    fix = "delete checkpoint.json and checkpoint-*.* to restart the run, or start a new run"
    if checkpoint["update"] > config.updates:
        raise ValueError(f"updates: the run already has {checkpoint['update']} updates, more than {config.updates}; "
                         f"pass --updates {checkpoint['update']} or more")
    try:
        state.agent.load_state_dict(checkpoint["agent"])
    except (KeyError, TypeError, ValueError) as error:
        raise ValueError(f"{where}: the state does not fit this run's agent ({error}); {fix}") from error
    state.update, state.episodes, state.best = checkpoint["update"], checkpoint["episodes"], checkpoint["best"]
    state.clock_start = time.perf_counter() - float(checkpoint["elapsed"])
    run.truncate_log(state.update)
    logger.info("resuming %s at update %d (%d episodes)", run.path, state.update, state.episodes)
    return False
