"""Evaluate a finished (or running) run: its policy against the imitation on the test contexts, with figures.

Writes into the run directory ``evaluation.json`` (per-context and mean return, the task's metrics by their keys,
validity, success where the env reports it and path smoothness relative to the imitation of both policies, with
95 % bootstrap intervals over the contexts; the task's metrics as its contract declares them), then
``evaluation.png`` (imitation and learned executed paths side by side in the first test context, the numbers with
their intervals; a figure that cannot be drawn is logged and leaves the evaluation written) and, on request,
``best_episode.mp4`` (the trained policy's best episode, re-run with the env's ``record_episode``).
"""

from __future__ import annotations

import json
import logging
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from rdmp_gym.envs.contract import TaskContract
from tqdm.auto import tqdm

from rdmp_gym.validation import check_choice

from .learners import CONTEXTUAL, policy_from_state
from .plots import plot_policy_comparison
from .pool import Evaluator
from .protocol import (
    PolicyScores,
    context_observations,
    defined_interval,
    defined_mean,
    evaluate_actions,
    final_test_seeds,
    path_jerk,
)
from .runs import RunDirectory, write_atomic
from .training import TrainConfig, load_run_config

__all__ = ["POLICIES", "compared_quantities", "evaluate_run", "record_best_episode", "trained_actions"]

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


def _clean(values: np.ndarray) -> list[float | None]:
    """JSON numbers, None for NaN."""
    return [None if not np.isfinite(v) else float(v) for v in np.asarray(values, dtype=np.float64)]


def _summary(scores: PolicyScores) -> dict[str, Any]:
    """Means over the contexts, 95 % bootstrap intervals of the means over contexts, per-context lists: the return,
    success (None where the env reports none), the task's metrics by their keys (``<key>_mean`` and ``<key>``), the
    path smoothness relative to the imitation's, validity and the failures."""
    rates = None if scores.success is None else scores.success.astype(np.float64)
    quantities = {"return": scores.returns, **({} if rates is None else {"success": rates}), **scores.metrics,
                  "jerk_ratio": scores.jerk_ratio}
    intervals = {name: found for name, values in quantities.items()
                 if (found := defined_interval(values, "mean")) is not None}

    def mean(values: np.ndarray) -> float | None:
        value = defined_mean(values)
        return None if np.isnan(value) else value

    metrics = scores.metrics
    return {"return_mean": mean(scores.returns), **{f"{key}_mean": mean(values) for key, values in metrics.items()},
            "valid_fraction": mean(scores.valid), "success_rate": None if rates is None else mean(rates),
            "jerk_ratio_mean": mean(scores.jerk_ratio), "intervals": intervals, "returns": _clean(scores.returns),
            **{key: _clean(values) for key, values in metrics.items()}, "valid": [bool(v) for v in scores.valid],
            "success": None if scores.success is None else [bool(v) for v in scores.success],
            "jerk_ratio": _clean(scores.jerk_ratio),
            "failures": None if scores.failures is None else [str(v) for v in scores.failures]}


def _declared(contract: TaskContract) -> dict[str, Any]:
    """What the evaluation's JSON says of the task: its metrics (key, label, direction, unit), success and the
    smoothness measure, so that a reader needs no env to show them."""
    return {"task": contract.name, "has_success": contract.has_success, "smoothness": contract.smoothness,
            "metrics": [{"key": m.key, "label": m.label, "higher_is_better": m.higher_is_better, "unit": m.unit}
                        for m in contract.metrics]}


def compared_quantities(result: dict[str, Any]) -> list[tuple[str, str]]:
    """``(interval key, label)`` of what an evaluation shows, in order: the return, the success rate (where the env
    reports success), the task's metrics by their labels and the path smoothness relative to the imitation's."""
    success = [("success", "success rate")] if result["has_success"] else []
    return [("return", "return"), *success, *((m["key"], m["label"]) for m in result["metrics"]),
            ("jerk_ratio", "jerk / imitation")]


def _figure(result: dict[str, Any], paths: dict[str, np.ndarray], contract: TaskContract, folder: Path,
            title: str) -> None:
    """``evaluation.png`` (an earlier one removed first); a figure that cannot be drawn is logged, not raised: the
    evaluation is written already."""
    target = folder / "evaluation.png"
    target.unlink(missing_ok=True)
    try:
        plot_policy_comparison(paths, {name: result[name] for name in paths}, target, title=title,
                               quantities=compared_quantities(result), labels=contract.path_labels, dt=contract.dt)
    except Exception as error:       # the figure is secondary to the numbers, which are written
        logger.warning("evaluation.png: the figure could not be drawn (%s: %s); evaluation.json holds the results",
                       type(error).__name__, error, exc_info=True)


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
        the contents of ``evaluation.json``: what the task declares (its metrics with their labels, success, the
        smoothness measure) and per policy the means over the test contexts, their 95 % bootstrap intervals over
        contexts, the success rate where the env reports success, the paths' smoothness relative to the
        imitation's, and the per-context lists.
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
        env, contract = evaluator.env, evaluator.contract
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
            paths[name] = np.asarray(env.unwrapped.executed_path(actions[0]), dtype=np.float64)
        result = {"run": str(run.path), "agent": config.agent, "policy": policy, "episodes": episodes,
                  "seeds": seeds.tolist(), **_declared(contract),
                  **{name: _summary(score) for name, score in scores.items()}}
        if video:
            best = int(np.argmax(scores["trained"].returns))
            result["video"] = str(_record(env, spec.options(), trained[best], int(seeds[best]), run.path))
    write_atomic(run.path / "evaluation.json", (json.dumps(result, indent=2) + "\n").encode())
    _figure(result, paths, contract, run.path,
            f"{config.agent} ({policy} policy) vs imitation on {episodes} test contexts")
    return result
