"""Training a cycle-by-cycle policy (:mod:`rdmp_gym.agents.learners.cycle_search`) on a task's cycle-level face.

``train_cycle_search(env_id, ...)`` runs the search on ``{Robot}{Task}Cycle-vN`` (the cycle face of an episodic id,
:func:`rdmp_gym.envs.registration.cycle_id`). The episodes of an update run in worker processes, each with its env.
Every few updates the mean policy is evaluated on validation contexts
(:func:`~rdmp_gym.agents.protocol.stratified_validation_seeds`); the best of those evaluations is kept and finally
scored on the test contexts (:func:`~rdmp_gym.agents.protocol.final_test_seeds`), which no training or selection
used. The same seed gives the same numbers, whatever the number of workers.
"""

from __future__ import annotations

import json
import os
import threading
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass, field
from multiprocessing import get_context
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from rdmp_gym.envs.registration import cycle_id

from .episodes import episode_metrics, failure_contexts
from .learners.contextual import action_layout
from .learners.cycle_search import CycleBatch, CycleSearch, CycleSearchConfig, act_with, stack_cycles
from .learners.smooth_exploration import block_layout
from .pool import watch_parent
from .protocol import (
    TRAIN_SEED_LIMIT,
    context_observations,
    final_test_seeds,
    interval,
    path_smoothness,
    stratified_validation_seeds,
)

__all__ = ["CycleActor", "CycleRun", "CycleRunner", "EpisodicPolicy", "cycle_episode", "cycle_scores",
           "executed_jerk_ratio", "failure_counts", "linear_actor", "summarise", "train_cycle_search"]

#: an action dimension acts in a cycle where its activation reaches this anywhere in the cycle
_ACTIVE = 1e-3


#: ``act(cycle, observation [o], previous [n] or None) -> action [n]``: a policy on a cycle face
CycleActor = Callable[[int, np.ndarray, "np.ndarray | None"], np.ndarray]
#: ``policy(contexts [E, c]) -> actions [E, n]``: an episodic policy (one action per context for the whole episode)
EpisodicPolicy = Callable[[np.ndarray], np.ndarray]


def linear_actor(policy: dict[str, np.ndarray], noise: np.ndarray | None = None) -> CycleActor:
    """The actor of a :meth:`~rdmp_gym.agents.learners.cycle_search.CycleSearch.policy` with exploration
    ``noise [C, n]`` (None: none)."""
    return lambda cycle, observation, previous: act_with(policy, cycle, observation, previous,
                                                         None if noise is None else noise[cycle])


def cycle_episode(env: Any, act: CycleActor, seed: int) -> dict[str, Any]:
    """One episode of the actor ``act`` on the cycle face ``env`` (unwrapped) in the context of reset seed ``seed``.

    Returns:
        ``observations [C, o]``, ``actions [C, n]`` (as executed; NaN rows for cycles not reached), ``spent [C]``
        (the cost before each cycle's start), ``jerk_ratio`` (the executed path's smoothness over the imitation's
        in the same context), ``refused`` (changes the task refused) and the episode's numbers
        (:func:`~rdmp_gym.agents.episodes.episode_metrics`).
    """
    observation, _ = env.reset(seed=int(seed))
    observations, previous = [], None
    for cycle in range(env.n_cycles):
        observations.append(observation)
        action = act(cycle, np.asarray(observation, dtype=np.float64), previous)
        observation, reward, terminated, _, info = env.step(action)
        previous = env.executed_actions[-1]
        if terminated:
            break
    result = episode_metrics(reward, info, env.task_contract())
    trace = result.pop("cost_trace")
    cycles = env.n_cycles
    result.update({"observations": stack_cycles(observations, cycles, env.observation_space.shape[0]),
                   "actions": stack_cycles(env.executed_actions, cycles, env.action_space.shape[0]),
                   "spent": np.array([trace[:step].sum() for step in env.start_steps]),
                   "jerk_ratio": executed_jerk_ratio(env), "refused": len(info.get("refused", ()))})
    return result


def executed_jerk_ratio(env: Any) -> float:
    """The smoothness of the path the episode executed over the imitation's in its context (the task's measure)."""
    face, contract = env.face, env.task_contract()
    if face.solution is None:
        return float("nan")
    executed = face.task.execution_path(face.solution.plan, face)
    imitation = face.task.execution_path(face.imitation_plan, face)
    return path_smoothness(executed, contract.smoothness, contract.dt) / max(
        path_smoothness(imitation, contract.smoothness, contract.dt), 1e-300)


_WORKER_ENV: Any = None


def _start_cycle_worker(env_id: str, env_kwargs: dict[str, Any], parent: int) -> None:
    global _WORKER_ENV
    # a worker whose run is killed exits at once instead of finishing the episodes queued for it
    threading.Thread(target=watch_parent, args=(parent,), daemon=True, name="parent-watchdog").start()
    os.environ.setdefault("MUJOCO_GL", "egl")
    import rdmp_gym.envs  # noqa: F401  (registers the ids)

    _WORKER_ENV = gym.make(env_id, **env_kwargs).unwrapped


def _cycle_worker_episode(policy: dict[str, np.ndarray], seed: int, noise: np.ndarray | None) -> dict[str, Any]:
    return cycle_episode(_WORKER_ENV, linear_actor(policy, noise), seed)


class CycleRunner:
    """Episodes of a cycle face: in this process (``workers=1``) or in ``workers`` processes, each with its env."""

    def __init__(self, env_id: str, env_kwargs: dict[str, Any] | None = None, workers: int = 1):
        if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
            raise ValueError(f"workers: expected an int >= 1, got {workers!r}")
        self.env_id, self.env_kwargs = env_id, dict(env_kwargs or {})
        self.env = gym.make(env_id, **self.env_kwargs).unwrapped
        self._pool = None if workers == 1 else ProcessPoolExecutor(
            workers, mp_context=get_context("spawn"), initializer=_start_cycle_worker,
            initargs=(env_id, self.env_kwargs, os.getpid()))

    def run(self, policy: dict[str, np.ndarray], seeds: Sequence[int], noises: np.ndarray | None = None
            ) -> list[dict[str, Any]]:
        """One :func:`cycle_episode` per seed (with ``noises[i]`` where given), in the seeds' order."""
        noise_rows = [None] * len(seeds) if noises is None else list(noises)
        if self._pool is None:
            return [cycle_episode(self.env, linear_actor(policy, n), s) for s, n in zip(seeds, noise_rows, strict=True)]
        return list(self._pool.map(_cycle_worker_episode, [policy] * len(seeds), seeds, noise_rows))

    def close(self) -> None:
        """Stop the workers and close the env."""
        if self._pool is not None:
            self._pool.shutdown()
        self.env.close()


@dataclass
class CycleRun:
    """What a run of :func:`train_cycle_search` measured.

    Attributes:
        curve: one row per evaluation: episodes used, validation success rate, validation mean return, exploration.
        test: the best policy's scores on the test contexts (success rate, return, metrics, jerk ratio, failures).
        best_episodes: the episodes after which the best validation policy was found.
        wall_seconds: the run's wall-clock time.
    """

    env_id: str
    seed: int
    config: dict[str, Any]
    curve: list[dict[str, float]] = field(default_factory=list)
    test: dict[str, Any] = field(default_factory=dict)
    best_episodes: int = 0
    wall_seconds: float = 0.0

    def save(self, path: str | Path) -> None:
        """Write the run as JSON."""
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        Path(path).write_text(json.dumps(asdict(self), indent=1))


def _layout(env: Any) -> tuple[np.ndarray, list[tuple[slice, bool | None]]]:
    """``(active [C, n], exploration blocks)`` of a cycle face: the action dimensions acting in each cycle."""
    weights = env.face.action_time_weights()                                         # [T, n]
    bounds = [*env.start_steps, env.face.n_steps]
    active = np.stack([weights[bounds[c]:max(bounds[c + 1], bounds[c] + 1)].max(axis=0) >= _ACTIVE
                       for c in range(env.n_cycles)])
    slices, n_dims = action_layout(env.face)
    return active, block_layout(slices, n_dims)


def _standardisation(observations: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(center [o], scale [o])`` of observations ``[M, o]`` (scale 0 where an entry does not vary)."""
    center, scale = observations.mean(axis=0), observations.std(axis=0)
    scale[scale < 1e-9 * (1.0 + np.abs(center))] = 0.0
    return center, scale


def cycle_scores(results: list[dict[str, Any]], seeds: np.ndarray) -> dict[str, Any]:
    """The per-context scores of evaluation episodes, and their means."""
    success = np.array([bool(r["success"]) for r in results])
    metrics = {key: [float(r["metrics"][key]) for r in results] for key in results[0]["metrics"]}
    return {"seeds": [int(s) for s in seeds], "success": success.tolist(), "success_rate": float(success.mean()),
            "returns": [r["return"] for r in results], "mean_return": float(np.mean([r["return"] for r in results])),
            "jerk_ratio": [r["jerk_ratio"] for r in results], "metrics": metrics,
            "failures": [r["failures"] for r in results]}


def train_cycle_search(env_id: str, *, episodes: int = 1000, rollouts: int = 16, seed: int = 0, workers: int = 2,
                       config: CycleSearchConfig | None = None, eval_every: int = 5, validation: int = 20,
                       test: int = 50, random_returns: bool = False, env_kwargs: dict[str, Any] | None = None,
                       progress: Callable[[int, dict[str, float]], None] | None = None, validation_pool: int = 400,
                       base: EpisodicPolicy | None = None) -> CycleRun:
    """Train the cycle-by-cycle search on ``env_id`` (an episodic id or its cycle face's) within ``episodes``
    training episodes of ``rollouts`` per update; ``random_returns``: the control that sees standard-normal costs
    instead of the episodes'. ``progress(episodes, row)`` after each evaluation; ``validation_pool``: the validation
    contexts the stratified choice sorts (:func:`~rdmp_gym.agents.protocol.stratified_validation_seeds`; its
    default is the other learners'); ``base``: an episodic policy whose action for the episode's context every
    cycle's action is taken around (the maps are then cycle-by-cycle changes of it; None: of the imitation).
    Returns what it measured."""
    config = config or CycleSearchConfig()
    face_id = env_id if "Cycle-v" in env_id else cycle_id(env_id)
    start = time.perf_counter()
    learner_seq, episode_seq, control_seq = np.random.SeedSequence(seed).spawn(3)
    episode_rng, control_rng = np.random.default_rng(episode_seq), np.random.default_rng(control_seq)
    runner = CycleRunner(face_id, env_kwargs, workers)
    try:
        env = runner.env
        active, blocks = _layout(env)
        size = env.observation_space.shape[0]
        zero = {"maps": np.zeros((env.n_cycles, env.action_space.shape[0], size + 1)), "center": np.zeros(size),
                "scale": np.zeros(size), "active": active}
        seeds = episode_rng.integers(0, TRAIN_SEED_LIMIT, rollouts)
        first = runner.run(zero, seeds, _offsets(env, base, seeds))                      # the start policy
        observed = np.concatenate([r["observations"] for r in first])
        center, scale = _standardisation(observed[np.all(np.isfinite(observed), axis=1)])
        search = CycleSearch(env.action_space.shape[0], env.face.observation_space.shape[0], active, center, scale,
                             blocks, config,
                             np.random.default_rng(learner_seq))
        validation_seeds = stratified_validation_seeds(env.face, validation, pool=max(validation_pool, validation))
        validation_offsets = _offsets(env, base, validation_seeds)
        run = CycleRun(face_id, seed, {"episodes": episodes, "rollouts": rollouts, "random_returns": random_returns,
                                       **config.to_dict()})
        chosen = _BestPolicy(runner, validation_seeds, validation_offsets, run, progress)
        used = rollouts
        if base is not None:
            chosen.consider(search, 0)                            # the base alone is a candidate
        while used + rollouts <= episodes:
            seeds = episode_rng.integers(0, TRAIN_SEED_LIMIT, rollouts)
            shared, own = search.exploration(rollouts)
            results = runner.run(search.policy(), seeds, _offsets(env, base, seeds) + shared[:, None, :] + own)
            costs = np.array([-r["return"] for r in results])
            if random_returns:
                costs = control_rng.standard_normal(rollouts)
            search.update(CycleBatch(np.stack([r["observations"] for r in results]), costs,
                                     np.stack([r["spent"] for r in results]), shared, own))
            used += rollouts
            if search.updates % eval_every == 0 or used + rollouts > episodes:
                chosen.consider(search, used)
        best = chosen.policy or search.policy()
        test_seeds = final_test_seeds(test)
        run.test = cycle_scores(runner.run(best, test_seeds, _offsets(env, base, test_seeds)), test_seeds)
        run.wall_seconds = time.perf_counter() - start
        return run
    finally:
        runner.close()


class _BestPolicy:
    """The best of a search's policies on the validation contexts (success rate, then mean return), each evaluation
    a row of the run's curve."""

    def __init__(self, runner: CycleRunner, seeds: np.ndarray, offsets: np.ndarray, run: CycleRun,
                 progress: Callable[[int, dict[str, float]], None] | None):
        self.runner, self.seeds, self.offsets, self.run, self.progress = runner, seeds, offsets, run, progress
        self.policy: dict[str, np.ndarray] | None = None
        self.key = (-1.0, -np.inf)

    def consider(self, search: CycleSearch, used: int) -> None:
        """Evaluate ``search``'s policy after ``used`` episodes, note the row and keep the policy if it is the best."""
        policy = search.policy()
        judged = cycle_scores(self.runner.run(policy, self.seeds, self.offsets), self.seeds)
        row = {"episodes": used, "validation_success": judged["success_rate"],
               "validation_return": judged["mean_return"], "sigma": search.sigma,
               "validation_failures": failure_counts(judged["failures"])}
        self.run.curve.append(row)
        if self.progress is not None:
            self.progress(used, row)
        key = (judged["success_rate"], judged["mean_return"])
        if key > self.key:
            self.policy, self.key, self.run.best_episodes = policy, key, used


def _offsets(env: Any, base: EpisodicPolicy | None, seeds: np.ndarray) -> np.ndarray:
    """``[N, C, n]`` the base policy's action for the context of each reset seed ``[N]``, in every cycle (0 without a
    base: the imitation)."""
    zero = np.zeros((len(seeds), env.n_cycles, env.action_space.shape[0]))
    if base is None:
        return zero
    actions = np.asarray(base(context_observations(env.face, seeds)), dtype=np.float64)
    if actions.shape != (len(seeds), zero.shape[2]) or not np.all(np.isfinite(actions)):
        raise ValueError(f"base: expected finite actions [{len(seeds)}, {zero.shape[2]}], got shape {actions.shape}")
    return zero + actions[:, None, :]


def failure_counts(failures: Sequence[str]) -> dict[str, int]:
    """``{cause: episodes}`` of per-episode failures (causes joined by ``"+"``, ``""`` for a success)."""
    return {cause: len(where) for cause, where in failure_contexts(list(failures)).items()}


def summarise(runs: Sequence[CycleRun]) -> dict[str, Any]:
    """Across runs (seeds): the test success rate's IQM with its 95 % interval, the mean jerk ratio, the episodes to
    validation success 0.8 and 0.9 (median over the runs that reach it, and how many do)."""
    success = np.array([r.test["success_rate"] for r in runs])

    def reach(level: float) -> dict[str, Any]:
        hits = [next((row["episodes"] for row in r.curve if row["validation_success"] >= level), None) for r in runs]
        reached = [h for h in hits if h is not None]
        return {"median": float(np.median(reached)) if reached else None, "runs": len(reached)}

    jerk = np.concatenate([np.asarray(r.test["jerk_ratio"], dtype=np.float64) for r in runs])
    return {"test_success": interval(success).to_dict(), "jerk_ratio": float(np.nanmean(jerk)),
            "episodes_to_0.8": reach(0.8), "episodes_to_0.9": reach(0.9), "runs": len(runs)}
