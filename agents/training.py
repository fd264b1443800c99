"""Training runs: one loop for every agent (update, evaluate the policy, log, checkpoint, keep the best).

An agent does one update per call of ``train_update`` (``rollouts`` training episodes) and maps
context observations to actions with ``policy_actions``. :class:`ESAgent` wraps the ask/tell learners
(PI², PI^BB, CMA-ES); ``rdmp_gym.agents.sb3.PPOAgent`` wraps stable-baselines3 PPO.

Seeds: the run seed makes a ``SeedSequence`` whose children drive the learner, the training episodes'
reset seeds (drawn from ``[0, 2**30)``), the perturbed start and the contexts that standardise a
contextual learner's features; the same config gives the same log. The policy is evaluated after every
update on the first ``eval_episodes`` validation contexts (:mod:`rdmp_gym.agents.protocol`), which no
training episode uses; "best" is chosen there, never on the test contexts.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Protocol

import numpy as np
from tqdm.auto import tqdm

from .evaluation import Evaluator
from .learners import CONTEXTUAL, LEARNERS, EpisodeBatch, Learner, SearchSpace, make_learner
from .options import check_choice, check_range, from_options, to_options
from .ppo_config import PPOConfig
from .protocol import TRAIN_SEED_LIMIT, context_observations, success, validation_seeds
from .runs import RunDirectory
from .sac_config import SACConfig
from .tasks import WIPE_ID, TaskSpec

__all__ = ["AGENTS", "ESAgent", "TrainConfig", "batch_summary", "train"]

logger = logging.getLogger(__name__)

AGENT_CONFIGS: dict[str, type] = {**{name: config for name, (_, config) in LEARNERS.items()}, "ppo": PPOConfig,
                                  "sac": SACConfig}
AGENTS = tuple(AGENT_CONFIGS)
START_MODES = ("imitation", "perturbed", "shrunk")
_FEATURE_CONTEXTS = 64   # training contexts whose mean and spread standardise a contextual learner's features
_SEED_LIMIT = 2**31 - 1


@dataclass(frozen=True)
class TrainConfig:
    """Everything that defines a training run (stored as ``config.json``).

    Attributes:
        agent: a learner of ``rdmp_gym.agents.learners.LEARNERS`` (``creps``, ``cpibb``, ``cpi2``, ``pi2``, ``pibb``,
            ``cmaes``, the baselines ``amplitude`` and ``random``), ``ppo`` or ``sac``.
        updates: number of updates.
        rollouts: training episodes per update.
        seed: run seed.
        workers: worker processes for the episodes (the black-box learners' numbers do not depend on it;
            PPO steps one env per worker, so its numbers do).
        env_id: the episodic env.
        env_kwargs: ``gym.make`` keywords (style, groups, n_periodic, n_transient, duration, ...).
        reset_options: options for every reset (e.g. a fixed context), or None.
        options: the agent's settings (fields of ``PI2Config``, ``PIBBConfig``, ``CMAESConfig``, ``PPOConfig``).
        start: ``imitation`` (the fitted DMP, ``a = 0``), ``perturbed`` (plus Gaussian noise of std
            ``perturbation`` in action units) or ``shrunk`` (the DMP weights scaled by ``1 - perturbation``:
            a smaller, damped movement; the initial conditions as fitted).
        perturbation: size of the perturbed or shrunk start.
        demo: a CSV/NPZ demonstration for the env to imitate instead of its built-in style ("" = none).
        eval_episodes: episodes that evaluate the policy after every update (fixed seeds).
        eval_every: evaluate the policy every this many updates (and after the last one).
        shared_context: all rollouts of one update use the same reset seed (same context); the contextual
            learners (``creps``, ``cpibb``, ``cpi2``, ``amplitude``, ``random``) always get one context per rollout.
    """

    agent: str = "pi2"
    updates: int = 30
    rollouts: int = 10
    seed: int = 0
    workers: int = 1
    env_id: str = WIPE_ID
    env_kwargs: dict[str, Any] = field(default_factory=dict)
    reset_options: dict[str, Any] | None = None
    options: dict[str, Any] = field(default_factory=dict)
    start: str = "imitation"
    perturbation: float = 0.3
    demo: str = ""
    eval_episodes: int = 1
    shared_context: bool = True
    eval_every: int = 1

    def __post_init__(self) -> None:
        check_choice(self.agent, "agent", AGENTS)
        check_range(self.updates, "updates", 1, None)
        check_range(self.rollouts, "rollouts", 2, None)
        check_range(self.seed, "seed", 0, _SEED_LIMIT)
        check_range(self.workers, "workers", 1, None)
        check_range(self.perturbation, "perturbation", 0.0, 1.0)
        check_range(self.eval_episodes, "eval_episodes", 1, None)
        check_range(self.eval_every, "eval_every", 1, None)
        check_choice(self.start, "start", START_MODES)
        for name in ("env_kwargs", "options"):
            if not isinstance(getattr(self, name), Mapping):
                raise TypeError(f"{name}: expected a mapping, got {type(getattr(self, name)).__name__}")
        if self.reset_options is not None and not isinstance(self.reset_options, Mapping):
            raise TypeError(f"reset_options: expected a mapping or None, got {type(self.reset_options).__name__}")
        from_options(AGENT_CONFIGS[self.agent], self.options, self.agent)  # fail early on a bad setting

    @classmethod
    def from_dict(cls, values: Mapping[str, Any]) -> TrainConfig:
        """Build from a mapping (e.g. ``config.json``); unknown keys are a ``ValueError``."""
        return from_options(cls, values, "config")

    def to_dict(self) -> dict[str, Any]:
        """JSON-friendly fields."""
        return to_options(self)

    @property
    def task(self) -> TaskSpec:
        """The task the run trains on."""
        return TaskSpec(self.env_id, dict(self.env_kwargs),
                        None if self.reset_options is None else dict(self.reset_options), self.demo)


class Agent(Protocol):
    """What the training loop needs from an agent."""

    @property
    def exploration(self) -> float: ...

    def train_update(self) -> EpisodeBatch: ...

    def policy_actions(self, observations: np.ndarray) -> np.ndarray: ...

    def state_dict(self) -> dict[str, Any]: ...

    def load_state_dict(self, state: dict[str, Any]) -> None: ...

    def close(self) -> None: ...


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


def _number(value: float) -> float | None:
    """A float for JSON; None for NaN."""
    value = float(value)
    return None if np.isnan(value) else value


def _nanmean(values: np.ndarray) -> float:
    return float(np.mean(values)) if np.all(np.isfinite(values)) else float("nan")


def batch_summary(batch: EpisodeBatch, prefix: str) -> dict[str, float | None]:
    """Mean/best return, mean coverage, force-in-band fraction, success rate and valid fraction of a batch."""
    return {f"{prefix}return_mean": _number(np.mean(batch.returns)),
            f"{prefix}success": _number(np.mean(success(batch))),
            f"{prefix}return_best": _number(np.max(batch.returns)),
            f"{prefix}coverage": _number(_nanmean(batch.coverage)),
            f"{prefix}force_in_band": _number(_nanmean(batch.force_in_band)),
            f"{prefix}valid": _number(np.mean(batch.valid))}


def _seed_streams(seed: int) -> dict[str, np.random.Generator]:
    names = ("learner", "episodes", "start", "features")
    children = np.random.SeedSequence(seed).spawn(len(names))
    return {name: np.random.default_rng(child) for name, child in zip(names, children, strict=True)}


def _initial_action(config: TrainConfig, evaluator: Evaluator, rng: np.random.Generator) -> np.ndarray:
    """``[n]`` the start (see ``TrainConfig.start``), clipped to the action box."""
    action = np.zeros(evaluator.n_actions)
    if config.start == "perturbed":
        action = config.perturbation * rng.standard_normal(action.size)
    elif config.start == "shrunk":
        base = evaluator.env.unwrapped
        theta = base.action_to_params(action)
        for name, part in base.dmp.param_slices(base.groups).items():
            if not name.startswith("initial"):
                theta[part] *= 1.0 - config.perturbation
        action = np.asarray(base.params_to_action(theta), dtype=np.float64)
    clipped = float(np.mean(np.abs(action) > 1.0))
    if clipped:
        logger.info("start: %.0f%% of the start action lies outside [-1, 1] and is clipped", 100 * clipped)
    return np.clip(action, -1.0, 1.0)


def _make_agent(config: TrainConfig, evaluator: Evaluator, streams: dict[str, np.random.Generator],
                initial: np.ndarray) -> Agent:
    if config.agent == "ppo":
        from .sb3 import PPOAgent

        return PPOAgent(config.task, initial, config.rollouts, config.workers, config.seed, config.options)
    if config.agent == "sac":
        from .sb3 import SACAgent

        return SACAgent(config.task, initial, config.rollouts, config.seed, config.options)
    base = evaluator.env.unwrapped
    weights = base.action_time_weights() if config.agent == "pi2" else None
    space = None
    if config.agent in CONTEXTUAL:
        seeds = streams["features"].integers(TRAIN_SEED_LIMIT, size=_FEATURE_CONTEXTS)
        space = SearchSpace.from_env(evaluator.env, context_observations(evaluator.env, seeds, config.task.options()))
    learner = make_learner(config.agent, initial, config.rollouts, streams["learner"], config.options, weights,
                           space)
    return ESAgent(learner, evaluator, streams["episodes"], config.shared_context)


def _resolve_config(config: TrainConfig | None, run: RunDirectory, resume: bool) -> TrainConfig:
    if not resume:
        if config is None:
            raise ValueError("config: required for a new run")
        if run.config_path.exists():
            raise FileExistsError(f"out: {run.path} already holds a run; pass --resume or choose another --out")
        return config
    saved = TrainConfig.from_dict(run.read_config())
    if config is None:
        return saved
    changed = sorted(name for name, value in config.to_dict().items()
                     if name not in ("updates", "workers") and value != saved.to_dict()[name])
    if changed:
        raise ValueError(f"resume: {changed} differ from the run's config.json; only updates and workers may change")
    return replace(saved, updates=config.updates, workers=config.workers)


def train(config: TrainConfig | None, out: str | Path, *, resume: bool = False, progress: bool = False
          ) -> RunDirectory:
    """Train an agent and write the run directory ``out`` (see :mod:`rdmp_gym.agents.runs`).

    Args:
        config: the run; with ``resume`` it may be None (use ``config.json``), or differ only in
            ``updates`` and ``workers``.
        out: run directory.
        resume: continue from the run's last checkpoint.
        progress: show a progress bar.
    Returns:
        the run directory.
    """
    run = RunDirectory(out)
    config = _resolve_config(config, run, resume)
    streams = _seed_streams(config.seed)
    with Evaluator(config.task, config.workers) as evaluator:
        initial = _initial_action(config, evaluator, streams["start"])
        eval_seeds = validation_seeds(config.eval_episodes)
        observations = np.stack([evaluator.env.reset(seed=int(s), options=config.task.options())[0]
                                 for s in eval_seeds])
        agent = _make_agent(config, evaluator, streams, initial)
        if not resume:
            run.create(config.to_dict())
        try:
            _loop(config, run, agent, evaluator, eval_seeds, observations, resume, progress)
        finally:
            agent.close()
    from .plots import plot_learning_curve

    plot_learning_curve(run.read_log(), run.curve_png, title=f"{config.agent} on {config.env_id}")
    return run


def _loop(config: TrainConfig, run: RunDirectory, agent: Agent, evaluator: Evaluator, eval_seeds: np.ndarray,
          observations: np.ndarray, resume: bool, progress: bool) -> None:
    state = run.load_checkpoint() if resume else None
    if state is None:
        update, episodes, best, elapsed = 0, 0, None, 0.0
        if resume:
            run.truncate_log(-1)   # killed before its first checkpoint: start over
    else:
        agent.load_state_dict(state["agent"])
        update, episodes, best, elapsed = state["update"], state["episodes"], state["best"], state["elapsed"]
        run.truncate_log(update)
        logger.info("resuming %s at update %d (%d episodes)", run.path, update, episodes)
    started = time.perf_counter() - elapsed

    def evaluate_and_log(batch: EpisodeBatch | None) -> None:
        nonlocal best
        record: dict[str, Any] = {"update": update, "episodes": episodes,
                                  "exploration": _number(agent.exploration)}
        if batch is not None:
            record.update(batch_summary(batch, ""))
        if update % config.eval_every and update < config.updates:
            record["best_eval_return"] = None if best is None else best["eval_return_mean"]
            record["time_s"] = round(time.perf_counter() - started, 3)
            run.append_log(record)
            run.save_checkpoint({"agent": agent.state_dict(), "update": update, "episodes": episodes,
                                 "best": best, "elapsed": record["time_s"]})
            return
        actions = agent.policy_actions(observations)
        evaluations = 1 + update // config.eval_every + (1 if update % config.eval_every else 0)
        record["eval_episodes"] = evaluations * len(eval_seeds)
        record.update(batch_summary(evaluator.run(actions, eval_seeds), "eval_"))
        if best is None or record["eval_return_mean"] > best["eval_return_mean"]:
            best = {**{k: v for k, v in record.items() if k.startswith("eval_")}, "update": update,
                    "eval_seed": int(eval_seeds[0])}
            params = evaluator.env.unwrapped.action_to_params(actions[0])
            run.save_best(actions[0], params, best)
        record["best_eval_return"] = best["eval_return_mean"]
        record["time_s"] = round(time.perf_counter() - started, 3)
        run.append_log(record)
        run.save_checkpoint({"agent": agent.state_dict(), "update": update, "episodes": episodes,
                             "best": best, "elapsed": record["time_s"]})

    if state is None:
        evaluate_and_log(None)
    bar = tqdm(total=config.updates, initial=update, disable=not progress, desc=config.agent, unit="update")
    with bar:
        while update < config.updates:
            batch = agent.train_update()
            update += 1
            episodes += batch.size
            evaluate_and_log(batch)
            bar.update(1)
            bar.set_postfix(ret=f"{best['eval_return_mean']:.3g}")
