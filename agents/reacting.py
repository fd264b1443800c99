"""The reacting learner: an open-loop policy for the parameters every cycle shares, then each cycle's change of it.

One budget of episodes, two stages:

1. **open loop** (the first ``open_loop`` share of the episodes): an episodic contextual learner (``bbrl`` with its
   structure-free settings, :data:`OPEN_LOOP_OPTIONS`) learns the DMP's parameters per context on the task's
   episodic face, one action per episode (:func:`rdmp_gym.agents.training.train`);
2. **reacting** (the rest): the cycle-by-cycle search (:func:`~rdmp_gym.agents.cycle_training.train_cycle_search`)
   learns, on the task's cycle-level face, each cycle's change of that policy's action from what is observed at
   the cycle's start (the context, the task's state), with the credit of the cost that follows the cycle's start.
   Its maps start at zero (every cycle runs the open-loop action), its exploration is each cycle's own
   (:data:`RESIDUAL`: no shared part, the open-loop stage has already searched the shared parameters; the cycles
   after the first share one map, whose gains on the task's state, the feedback, accumulate).

The best validation policy of the second stage (its start, the open-loop policy alone, included) is scored on the
test contexts; the curve holds both stages, against the episodes used.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np
from rdmp_gym.envs.registration import cycle_id

from .cycle_training import CycleRun, failure_counts, train_cycle_search
from .learners import policy_from_state
from .learners.cycle_search import CycleSearchConfig
from .pool import Evaluator
from .protocol import context_observations, evaluate_actions, final_test_seeds
from .runs import RunDirectory
from .training import TrainConfig, load_run_config, train

__all__ = ["OPEN_LOOP_OPTIONS", "RESIDUAL", "open_loop_curve", "score_open_loop", "train_reacting"]

#: the open-loop stage's learner settings: ``bbrl`` without task structure, its linear part in closed form
OPEN_LOOP_OPTIONS: dict[str, Any] = {"linear": True, "linear_fit": "ridge", "epsilon": 1.0}
#: the reacting stage's search: each cycle's own exploration around the open-loop action, one map for the cycles
#: after the first, its feedback gains accumulated (measured on ``ArmarWipe-v3``, 3 seeds: test success 0.79 against
#: 0.71 with one map per cycle and each update's own feedback, jerk 1.13 against 1.23)
RESIDUAL = CycleSearchConfig(sigma=0.1, shared=0.0, min_sigma=0.02, pooled=True, feedback_keep=1.0)


def train_reacting(env_id: str, out: str | Path, *, episodes: int = 1000, open_loop: float = 0.6, seed: int = 0,
                   workers: int = 2, rollouts: int = 20, validation: int = 10, test: int = 50,
                   options: Mapping[str, Any] | None = None, residual: CycleSearchConfig | None = None,
                   progress: Callable[[int, dict[str, float]], None] | None = None) -> CycleRun:
    """Train the reacting learner on the episodic task ``env_id`` within ``episodes`` episodes (see the module
    docstring); the open-loop stage's run directory is ``out / "open_loop"`` (a run there with the same settings is
    continued, or reused where it has finished). ``options``: the open-loop learner's
    settings (default :data:`OPEN_LOOP_OPTIONS`), ``residual``: the reacting stage's (default :data:`RESIDUAL`).
    Returns the reacting stage's run, its curve preceded by the open-loop stage's."""
    if not 0.0 < open_loop < 1.0:
        raise ValueError(f"open_loop: expected a share in (0, 1) of the episodes, got {open_loop!r}")
    updates = int(open_loop * episodes) // rollouts
    if updates < 1 or episodes - updates * rollouts < 2 * rollouts:
        raise ValueError(f"episodes: {episodes} leave no room for both stages at {rollouts} rollouts per update")
    config = TrainConfig(agent="bbrl", env_id=env_id, updates=updates, rollouts=rollouts, seed=seed, workers=workers,
                         env_kwargs={}, options=dict(OPEN_LOOP_OPTIONS if options is None else options),
                         eval_episodes=validation, eval_every=5, shared_context=False, stratified_validation=True)
    stage = Path(out) / "open_loop"
    run_dir = train(config, stage, resume=(stage / "config.json").exists())
    used = updates * rollouts
    state = run_dir.load_checkpoint()["agent"]["learner"]

    def base(contexts: np.ndarray) -> np.ndarray:
        return policy_from_state(state, contexts)

    def shifted(episodes_used: int, row: dict[str, float]) -> None:
        if progress is not None:
            progress(used + episodes_used, row)

    run = train_cycle_search(cycle_id(env_id), episodes=episodes - used, rollouts=rollouts, seed=seed,
                             workers=workers, config=residual or RESIDUAL, validation=validation, test=test,
                             progress=shifted, base=base)
    run.curve = open_loop_curve(run_dir.read_log()) + [{**row, "episodes": row["episodes"] + used}
                                                        for row in run.curve]
    run.best_episodes += used
    run.config = {"open_loop": {"agent": "bbrl", "episodes": used, **config.options.to_dict()}, **run.config}
    return run


def open_loop_curve(log: list[dict[str, Any]]) -> list[dict[str, float]]:
    """The evaluated rows of an episodic run's log as the cycle runs' curve rows (episodes, validation success and
    return)."""
    return [{"episodes": int(row["episodes"]), "validation_success": float(row["eval_success"]),
             "validation_return": float(row["eval_return_mean"]), "stage": "open loop"}
            for row in log if row.get("eval_success") is not None]


def score_open_loop(stage: str | Path, test: int = 50, workers: int = 2) -> dict[str, Any]:
    """The open-loop stage's final policy (run directory ``stage``) alone on the ``test`` test contexts: what the
    reacting stage started from. Returns the success rate, the per-context success, the mean jerk ratio, the task's
    metrics' means and the failure causes."""
    run = RunDirectory(stage)
    config = load_run_config(run)
    state = run.load_checkpoint()["agent"]["learner"]
    seeds = final_test_seeds(test)
    with Evaluator(config.task, workers) as evaluator:
        observations = context_observations(evaluator.env, seeds, config.task.options())
        scores = evaluate_actions(evaluator, policy_from_state(state, observations), seeds)
    success = np.asarray(scores.success, dtype=bool)
    return {"success_rate": float(success.mean()), "success": success.tolist(),
            "jerk_ratio": float(np.nanmean(scores.jerk_ratio)),
            "metrics": {key: float(np.nanmean(values)) for key, values in scores.metrics.items()},
            "failures": failure_counts([] if scores.failures is None else [str(f) for f in scores.failures])}
