"""Evaluate a finished (or running) run: its policy against the imitation on fixed seeds, with figures.

Writes into the run directory ``evaluation.json`` (per-episode and mean return, coverage, force in
band, validity of both policies), ``evaluation.png`` (sponge paths in the first context, mean
metrics) and, on request, ``best_episode.mp4`` (the trained policy's best episode, re-run with the
env's ``record_episode``).
"""

from __future__ import annotations

import json
import logging
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from tqdm.auto import tqdm

from .evaluation import Evaluator
from .learners.base import EpisodeBatch
from .options import check_choice
from .plots import plot_evaluation
from .runs import RunDirectory, write_atomic
from .training import TrainConfig, load_run_config

__all__ = ["POLICIES", "evaluate_run", "record_best_episode"]

logger = logging.getLogger(__name__)

POLICIES = ("best", "last")


def _trained_actions(run: RunDirectory, config: TrainConfig, policy: str, observations: np.ndarray,
                     n_actions: int) -> np.ndarray:
    """``[E, n]`` the run's actions for the contexts ``observations [E, o]``."""
    if policy == "best":
        return np.repeat(run.load_best(n_actions)[None], len(observations), axis=0)
    state = run.load_checkpoint()
    if state is None:
        raise FileNotFoundError(f"run: {run.path} has no checkpoint yet")
    if config.agent == "ppo":
        from .sb3 import PPOAgent

        agent = PPOAgent(config.task, np.zeros(n_actions), config.rollouts, 1, config.seed, config.options)
        try:
            agent.load_state_dict(state["agent"])
            return agent.policy_actions(observations)
        finally:
            agent.close()
    mean = np.asarray(state["agent"]["learner"]["mean"], dtype=np.float64)
    if mean.shape != (n_actions,) or not np.all(np.isfinite(mean)):
        raise ValueError(f"{run.checkpoint_path}: the policy mean has shape {mean.shape}, expected ({n_actions},)")
    return np.repeat(mean[None], len(observations), axis=0)


def _record(env: gym.Env, options: dict[str, Any] | None, action: np.ndarray, seed: int, folder: Path) -> Path:
    """Re-run one episode with the env's ``record_episode`` and write ``folder / best_episode.mp4``."""
    if not hasattr(env.unwrapped, "record_episode"):
        raise ValueError(f"video: {env.spec.id if env.spec else env} has no recording API (record_episode)")
    env.reset(seed=seed, options=options)
    target = folder / "best_episode.mp4"
    env.unwrapped.record_episode(np.asarray(action, dtype=np.float32), target)
    logger.info("wrote %s", target)
    return target


def record_best_episode(path: str | Path) -> Path:
    """Record the run's best policy (``best_params.npy``) in the first evaluation context of training,
    as ``best_episode.mp4`` in the run directory."""
    run = RunDirectory(path)
    config = load_run_config(run)
    seed = run.best_summary()["eval_seed"]
    run.check_writable()
    env = config.task.make()
    try:
        return _record(env, config.task.options(), run.load_best(env.action_space.shape[0]), seed, run.path)
    finally:
        env.close()


def _run_chunks(evaluator: Evaluator, actions: np.ndarray, seeds: np.ndarray, bar: tqdm) -> EpisodeBatch:
    size = 2 * evaluator.workers
    parts = []
    for start in range(0, len(seeds), size):
        parts.append(evaluator.run(actions[start:start + size], seeds[start:start + size]))
        bar.update(len(parts[-1].returns))
    return EpisodeBatch(*(np.concatenate([getattr(p, name) for p in parts])
                          for name in ("actions", "returns", "cost_traces", "coverage", "force_in_band",
                                       "valid", "seeds")))


def _summary(batch: EpisodeBatch) -> dict[str, Any]:
    def clean(values: np.ndarray) -> list[float | None]:
        return [None if not np.isfinite(v) else float(v) for v in values.astype(np.float64)]

    def mean(values: np.ndarray) -> float | None:
        return float(np.mean(values)) if np.all(np.isfinite(values)) else None

    return {"return_mean": mean(batch.returns), "coverage_mean": mean(batch.coverage),
            "force_in_band_mean": mean(batch.force_in_band), "valid_fraction": mean(batch.valid),
            "returns": clean(batch.returns), "coverage": clean(batch.coverage),
            "force_in_band": clean(batch.force_in_band), "valid": [bool(v) for v in batch.valid]}


def evaluate_run(path: str | Path, episodes: int = 10, *, seed: int = 12345, workers: int = 1,
                 policy: str = "best", video: bool = False, progress: bool = False, backend: str = "local",
                 ray_address: str | None = None) -> dict[str, Any]:
    """Evaluate the run at ``path`` and the imitation on the same ``episodes`` reset seeds.

    Args:
        path: a run directory written by :func:`rdmp_gym.agents.training.train`.
        episodes: evaluation episodes per policy.
        seed: draws the reset seeds (contexts).
        workers: worker processes (or Ray actors).
        policy: ``best`` (``best_params.npy``) or ``last`` (the last checkpoint's policy; PPO: its network).
        video: also write ``best_episode.mp4`` (needs an env with ``record_episode``, e.g. ArmarWipe).
        progress: show a progress bar.
        backend, ray_address: where the episodes run (see :class:`Evaluator`).
    Returns:
        the contents of ``evaluation.json``.
    """
    check_choice(policy, "policy", POLICIES)
    if isinstance(episodes, bool) or not isinstance(episodes, int) or episodes < 1:
        raise ValueError(f"episodes: expected a positive int, got {episodes!r}")
    run = RunDirectory(path)
    config = load_run_config(run)
    run.check_writable()             # before any episode is run
    spec = config.task
    seeds = np.random.default_rng(seed).integers(2**31 - 1, size=episodes)
    with Evaluator(spec, workers, backend, ray_address) as evaluator:
        env = evaluator.env
        observations = np.stack([env.reset(seed=int(s), options=spec.options())[0] for s in seeds])
        trained = _trained_actions(run, config, policy, observations, evaluator.n_actions)
        imitation = np.zeros_like(trained)
        with tqdm(total=2 * episodes, disable=not progress, desc="evaluate", unit="episode") as bar:
            batches = {"imitation": _run_chunks(evaluator, imitation, seeds, bar),
                       "trained": _run_chunks(evaluator, trained, seeds, bar)}
        env.reset(seed=int(seeds[0]), options=spec.options())
        base = env.unwrapped
        paths = {name: base.rollout_path(base.action_to_params(actions[0]))
                 for name, actions in (("imitation", imitation), ("trained", trained))}
        result = {"run": str(run.path), "agent": config.agent, "policy": policy, "episodes": episodes,
                  "seeds": seeds.tolist(), **{name: _summary(batch) for name, batch in batches.items()}}
        if video:
            best = int(np.argmax(batches["trained"].returns))
            result["video"] = str(_record(env, spec.options(), trained[best], int(seeds[best]), run.path))
    metrics = {name: {key: value for key, value in (("return", result[name]["return_mean"]),
                                                    ("coverage", result[name]["coverage_mean"]),
                                                    ("force in band", result[name]["force_in_band_mean"]))
                      if value is not None}
               for name in batches}
    plot_evaluation(paths, metrics, run.path / "evaluation.png",
                    title=f"{config.agent} ({policy}) vs imitation, {episodes} episodes")
    write_atomic(run.path / "evaluation.json", (json.dumps(result, indent=2) + "\n").encode())
    return result
