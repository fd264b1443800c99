"""Evaluate a finished (or running) run: its policy against the imitation on the test contexts, with figures.

Writes into the run directory ``evaluation.json`` (per-context and mean return, coverage, force in
band, validity, success and path jerk relative to the imitation of both policies, with 95 % bootstrap
intervals over the contexts), ``evaluation.png`` (imitation and learned sponge paths side by side in
the first test context, the metrics with their intervals) and, on request, ``best_episode.mp4`` (the
trained policy's best episode, re-run with the env's ``record_episode``).
"""

from __future__ import annotations

import json
import logging
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from tqdm.auto import tqdm

from rdmp_gym.validation import check_choice

from .learners import CONTEXTUAL, policy_from_state
from .plots import plot_policy_comparison
from .pool import Evaluator
from .protocol import PolicyScores, context_observations, evaluate_actions, final_test_seeds, interval, path_jerk
from .runs import RunDirectory, write_atomic
from .training import TrainConfig, load_run_config

__all__ = ["POLICIES", "evaluate_run", "record_best_episode", "trained_actions"]

logger = logging.getLogger(__name__)

POLICIES = ("last", "best")


def trained_actions(run: RunDirectory, config: TrainConfig, policy: str, observations: np.ndarray,
                    n_actions: int) -> np.ndarray:
    """``[E, n]`` the run's actions for the contexts ``observations [E, o]``."""
    if policy == "best":
        if config.agent in CONTEXTUAL:
            raise ValueError(f"policy: {config.agent} is contextual; its 'best' action holds for one context only, "
                             "evaluate the final policy (--policy last)")
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
    if config.agent == "sac":
        from .sb3 import SACAgent

        agent = SACAgent(config.task, np.zeros(n_actions), config.rollouts, config.seed, config.options)
        try:
            agent.load_state_dict(state["agent"])
            return agent.policy_actions(observations)
        finally:
            agent.close()
    if config.agent in CONTEXTUAL:
        return policy_from_state(state["agent"]["learner"], observations)
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


def _summary(scores: PolicyScores) -> dict[str, Any]:
    """Means over the contexts, 95 % bootstrap intervals of the means over contexts, per-context lists."""
    def clean(values: np.ndarray) -> list[float | None]:
        return [None if not np.isfinite(v) else float(v) for v in np.asarray(values, dtype=np.float64)]

    def mean(values: np.ndarray) -> float | None:
        values = np.asarray(values, dtype=np.float64)
        return float(np.mean(values)) if np.all(np.isfinite(values)) else None

    intervals = {name: interval(getattr(scores, name).astype(np.float64), "mean").to_dict()
                 for name in ("success", "coverage", "jerk_ratio") if np.all(np.isfinite(getattr(scores, name)))}
    return {"return_mean": mean(scores.returns), "coverage_mean": mean(scores.coverage),
            "force_in_band_mean": mean(scores.force_in_band), "valid_fraction": mean(scores.valid),
            "success_rate": mean(scores.success), "jerk_ratio_mean": mean(scores.jerk_ratio),
            "intervals": intervals, "returns": clean(scores.returns), "coverage": clean(scores.coverage),
            "force_in_band": clean(scores.force_in_band), "valid": [bool(v) for v in scores.valid],
            "success": [bool(v) for v in scores.success], "jerk_ratio": clean(scores.jerk_ratio),
            "failures": None if scores.failures is None else [str(v) for v in scores.failures]}


def evaluate_run(path: str | Path, episodes: int = 20, *, workers: int = 1, policy: str = "last",
                 video: bool = False, progress: bool = False, backend: str = "local",
                 ray_address: str | None = None) -> dict[str, Any]:
    """Evaluate the run at ``path`` and the imitation on the first ``episodes`` test contexts
    (:func:`rdmp_gym.agents.protocol.final_test_seeds`: never used in training or selection).

    Args:
        path: a run directory written by :func:`rdmp_gym.agents.training.train`.
        episodes: test contexts (one episode per policy each).
        workers: worker processes (or Ray actors).
        policy: ``last`` (the final policy; PPO: its network; contextual learners: θ̄ + K·φ(s)) or
            ``best`` (``best_params.npy``, chosen on the validation contexts; shared-θ learners only).
        video: also write ``best_episode.mp4`` (needs an env with ``record_episode``, e.g. ArmarWipe).
        progress: show a progress bar.
        backend, ray_address: where the episodes run (see :class:`Evaluator`).
    Returns:
        the contents of ``evaluation.json``: per policy the means over the test contexts, their 95 %
        bootstrap intervals over contexts, success rate, the paths' jerk relative to the imitation's,
        and the per-context lists.
    """
    check_choice(policy, "policy", POLICIES)
    if isinstance(episodes, bool) or not isinstance(episodes, int) or episodes < 1:
        raise ValueError(f"episodes: expected a positive int, got {episodes!r}")
    run = RunDirectory(path)
    config = load_run_config(run)
    run.check_writable()             # before any episode is run
    spec = config.task
    seeds = final_test_seeds(episodes)
    with Evaluator(spec, workers, backend, ray_address) as evaluator:
        env = evaluator.env
        observations = context_observations(env, seeds, spec.options())
        trained = trained_actions(run, config, policy, observations, evaluator.n_actions)
        imitation = np.zeros_like(trained)
        reference = np.array([path_jerk(env, imitation[0], s, spec.options()) for s in seeds])
        scores = {}
        with tqdm(total=2, disable=not progress, desc="evaluate", unit="policy") as bar:
            for name, actions in (("imitation", imitation), ("trained", trained)):
                scores[name] = evaluate_actions(evaluator, actions, seeds, reference)
                bar.update(1)
        paths = {}
        for name, actions in (("imitation", imitation), ("trained", trained)):
            env.reset(seed=int(seeds[0]), options=spec.options())
            paths[name] = env.unwrapped.rollout_path(env.unwrapped.action_to_params(actions[0]))
        result = {"run": str(run.path), "agent": config.agent, "policy": policy, "episodes": episodes,
                  "seeds": seeds.tolist(), **{name: _summary(score) for name, score in scores.items()}}
        if video:
            best = int(np.argmax(scores["trained"].returns))
            result["video"] = str(_record(env, spec.options(), trained[best], int(seeds[best]), run.path))
    plot_policy_comparison(paths, {name: result[name] for name in scores}, run.path / "evaluation.png",
                           title=f"{config.agent} ({policy} policy) vs imitation on {episodes} test contexts")
    write_atomic(run.path / "evaluation.json", (json.dumps(result, indent=2) + "\n").encode())
    return result
