"""Callbacks of the training loop: what happens around the updates (evaluation, the best policy, log, checkpoints).

The loop of :func:`rdmp_gym.agents.training.train` runs updates and calls every callback at three points, in
the order of the list:

* ``on_training_start(state)``: once, before the first update (after a resumed run was restored);
* ``on_update(state)``: after each update, and once for the start (update 0, ``state.batch`` None) of a new run;
  a callback that returns ``False`` stops training after this update (the others still run for it);
* ``on_training_end(state)``: once when the loop ends, also when an update or a callback raised.

Each sees the one :class:`TrainingState` of the run: the configuration, the run directory, the agent, the
episode pool, the counters, the update's batch, the log line the callbacks fill in (``state.record``) and the
best policy so far. The default set (:func:`default_callbacks`), in this order, writes a run directory:

=========================  ==================================================================================
:class:`EvaluateCallback`  evaluates the policy on the validation contexts every ``eval_every`` updates
:class:`BestPolicyCallback`  keeps the best evaluated policy: ``best_params.npy``/``.json`` and ``dmp.json``
:class:`LogCallback`       writes ``state.record`` with the update's own numbers as a line of ``log.jsonl``
:class:`CheckpointCallback`  replaces the checkpoint (``--resume`` continues from it)
:class:`FirstUpdateGuard`  stops a run whose first update had no valid episode (:class:`NoValidEpisodesError`)
:class:`ProgressBar`       the progress bar (when ``train(progress=True)``)
=========================  ==================================================================================

``train(..., callbacks=[...])`` runs the given callbacks after the default set; one that is an instance of a
default's class (a subclass, say) takes that default's place instead. Callbacks hold no state that a resumed
run needs, except through ``state`` (the best policy travels in the checkpoint).
"""

from __future__ import annotations

import time
from collections import Counter
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from tqdm.auto import tqdm

from rdmp_gym import save_dmp

from .errors import NoValidEpisodesError
from .learners import EpisodeBatch
from .pool import Evaluator
from .protocol import defined_mean, success
from .runs import RunDirectory
from .train_config import Agent, TrainConfig

__all__ = ["BestPolicyCallback", "Callback", "CallbackList", "CheckpointCallback", "EvaluateCallback",
           "FirstUpdateGuard", "LogCallback", "NoValidEpisodesError", "PolicyEvaluation", "ProgressBar",
           "TrainingState", "batch_summary", "default_callbacks", "invalid_reasons",
           "merge_callbacks"]


@dataclass(frozen=True)
class PolicyEvaluation:
    """The policy's evaluation after one update: ``actions [E, n]`` on the validation contexts, their episodes
    and the ``eval_*`` numbers of the log line."""

    actions: np.ndarray
    batch: EpisodeBatch
    summary: dict[str, Any]


@dataclass
class TrainingState:
    """The run as the callbacks see it (one object for the whole run; the loop advances it).

    Attributes:
        config: the run's configuration.
        run: the run directory.
        agent: the agent being trained.
        evaluator: the episode pool of the run (its ``env`` maps actions to DMP parameters).
        validation_seeds: ``[E]`` reset seeds of the validation contexts (``config.eval_episodes``).
        validation_observations: ``[E, o]`` their context observations.
        update: the updates done (0 before the first).
        episodes: the training episodes run.
        best: the best evaluated policy's ``eval_*`` numbers, ``update`` and ``eval_seed`` (None before the
            first evaluation); saved in the checkpoint.
        clock_start: ``time.perf_counter()`` at which the run's clock read 0 (a resumed run's clock goes on).
        batch: the last update's training episodes (None for the start, update 0).
        record: the update's log line as the callbacks fill it in (reset by the loop before each update's calls).
        evaluation: the policy's evaluation of this update, if a callback evaluated it (reset with ``record``).
        stopped: set by the loop when a callback stopped training before ``config.updates``.
    """

    config: TrainConfig
    run: RunDirectory
    agent: Agent
    evaluator: Evaluator
    validation_seeds: np.ndarray
    validation_observations: np.ndarray
    update: int = 0
    episodes: int = 0
    best: dict[str, Any] | None = None
    clock_start: float = field(default_factory=time.perf_counter)
    batch: EpisodeBatch | None = None
    record: dict[str, Any] = field(default_factory=dict)
    evaluation: PolicyEvaluation | None = None
    stopped: bool = False

    def elapsed(self) -> float:
        """Seconds on the run's clock, to the millisecond (a resumed run's clock goes on from its checkpoint)."""
        return round(time.perf_counter() - self.clock_start, 3)


class Callback:
    """A callback of the training loop; every hook does nothing unless overridden (see the module docstring)."""

    def on_training_start(self, state: TrainingState) -> None:
        """Once, before the first update of this call of ``train`` (a resumed run is restored already)."""

    def on_update(self, state: TrainingState) -> bool | None:
        """After each update (and for the start of a new run, update 0); ``False`` stops training."""
        return None

    def on_training_end(self, state: TrainingState) -> None:
        """Once when the loop ends: all updates done, stopped by a callback, or an error raised."""


class CallbackList(Callback):
    """Callbacks called one after the other, in order.

    Args:
        callbacks: the callbacks.
    """

    def __init__(self, callbacks: Iterable[Callback]) -> None:
        self.callbacks = list(callbacks)
        for callback in self.callbacks:
            if not isinstance(callback, Callback):
                raise TypeError(f"callbacks: expected Callback instances, got {type(callback).__name__}")

    def on_training_start(self, state: TrainingState) -> None:
        for callback in self.callbacks:
            callback.on_training_start(state)

    def on_update(self, state: TrainingState) -> bool:
        """Every callback's ``on_update``; False if any of them returned False."""
        go_on = True
        for callback in self.callbacks:
            go_on = callback.on_update(state) is not False and go_on
        return go_on

    def on_training_end(self, state: TrainingState) -> None:
        for callback in self.callbacks:
            callback.on_training_end(state)


def _number(value: float) -> float | None:
    """A float for JSON; None for NaN."""
    value = float(value)
    return None if np.isnan(value) else value


#: the numbers of :func:`batch_summary` beside the task's metrics (a metric may not take these names)
_SUMMARY = ("return_mean", "success", "return_best", "valid")


def batch_summary(batch: EpisodeBatch, prefix: str) -> dict[str, float | None]:
    """Mean and best return, success rate (None where the env reports no success), valid fraction and the mean of
    each of the task's metrics over the episodes that have it (keyed by the metric's key, e.g. the wiping task's
    ``coverage``) of a batch, each key prefixed with ``prefix``."""
    clash = sorted(set(batch.metrics) & set(_SUMMARY))
    if clash:
        raise ValueError(f"batch.metrics: the task's metric keys {clash} are names of the summary {list(_SUMMARY)}")
    rate = success(batch)
    return {f"{prefix}return_mean": _number(np.mean(batch.returns)),
            f"{prefix}success": None if rate is None else _number(np.mean(rate)),
            f"{prefix}return_best": _number(np.max(batch.returns)),
            **{f"{prefix}{key}": _number(defined_mean(values)) for key, values in batch.metrics.items()},
            f"{prefix}valid": _number(np.mean(batch.valid))}


class EvaluateCallback(Callback):
    """Evaluate the policy on the validation contexts after every ``config.eval_every`` updates, the start and
    the last update: sets ``state.evaluation`` and the ``eval_*`` numbers of ``state.record``
    (``eval_episodes`` counts the evaluation episodes of the run so far)."""

    def due(self, state: TrainingState) -> bool:
        """Whether the policy is evaluated after this update."""
        every = state.config.eval_every
        return state.update % every == 0 or state.update >= state.config.updates

    def on_update(self, state: TrainingState) -> None:
        if not self.due(state):
            return
        every, seeds = state.config.eval_every, state.validation_seeds
        actions = state.agent.policy_actions(state.validation_observations)
        batch = state.evaluator.run(actions, seeds)
        evaluations = 1 + state.update // every + (1 if state.update % every else 0)
        summary = {"eval_episodes": evaluations * len(seeds), **batch_summary(batch, "eval_")}
        state.evaluation = PolicyEvaluation(actions, batch, summary)
        state.record.update(summary)


class BestPolicyCallback(Callback):
    """Keep the best evaluated policy (highest mean validation return; the earlier one on a tie) in ``state.best``
    and the run directory: ``best_params.npy``, ``best_params.json`` and ``dmp.json``, the DMP the env executes for
    the best policy's parameters (``env.unwrapped.policy_dmp(theta)``; core format: ``gym.make(env_id, dmp=path)``,
    ``rdmp_gym.load_dmp``; an env without ``policy_dmp`` writes none). Sets ``best_eval_return`` in every log
    line."""

    def on_update(self, state: TrainingState) -> None:
        found, best = state.evaluation, state.best
        if found is not None and (best is None or found.summary["eval_return_mean"] > best["eval_return_mean"]):
            state.best = {**found.summary, "update": state.update, "eval_seed": int(state.validation_seeds[0])}
            env = state.evaluator.env.unwrapped
            params = env.action_to_params(found.actions[0])
            state.run.save_best(found.actions[0], params, state.best)
            policy_dmp = getattr(env, "policy_dmp", None)
            if policy_dmp is not None:
                save_dmp(policy_dmp(params), state.run.path / "dmp.json")
        state.record["best_eval_return"] = None if state.best is None else state.best["eval_return_mean"]


class LogCallback(Callback):
    """Append the update's line to ``log.jsonl``: the update's own numbers (``update``, ``episodes``,
    ``exploration``, the training batch's summary), what the callbacks before it put in ``state.record``, and
    ``time_s`` (the run's clock)."""

    def on_update(self, state: TrainingState) -> None:
        own = {"update": state.update, "episodes": state.episodes, "exploration": _number(state.agent.exploration)}
        if state.batch is not None:
            own.update(batch_summary(state.batch, ""))
        state.record = {**own, **state.record, "time_s": state.elapsed()}
        state.run.append_log(state.record)


class CheckpointCallback(Callback):
    """Replace the run's checkpoint after every update (the agent's state, the counters, the best policy and the
    clock): what ``train(..., resume=True)`` continues from. Runs after the log (see :mod:`rdmp_gym.agents.runs`)."""

    def on_update(self, state: TrainingState) -> None:
        elapsed = state.record.get("time_s", state.elapsed())
        state.run.save_checkpoint({"agent": state.agent.state_dict(), "update": state.update,
                                   "episodes": state.episodes, "best": state.best, "elapsed": elapsed})


class FirstUpdateGuard(Callback):
    """Stop with :class:`NoValidEpisodesError` (the counted ``invalid_reason``s and a hint) if every episode of the
    first update was invalid (a demonstration in millimetres, say): the learner would only see a constant
    penalty. The update is logged and checkpointed first."""

    def on_update(self, state: TrainingState) -> None:
        batch = state.batch
        if state.update != 1 or batch is None or np.any(batch.valid):
            return
        reasons = invalid_reasons(state.evaluator, state.config, batch, int(state.validation_seeds[0]))
        raise NoValidEpisodesError(
            f"training: all {batch.size} episodes of the first update were invalid (invalid_reason: "
            f"{', '.join(f'{k} x{v}' for k, v in reasons.items())}); the learner would only see a constant "
            "penalty. Check the demonstration's units (metres, table frame) and the env settings; "
            f"the run stopped at update 1 in {state.run.path}")


def invalid_reasons(evaluator: Evaluator, config: TrainConfig, batch: EpisodeBatch, fallback_seed: int
                    ) -> dict[str, int]:
    """Re-run the (cheap, unsimulated) invalid episodes of ``batch`` here and count their ``info['invalid_reason']``
    (``fallback_seed`` for episodes without a seed)."""
    env, counts = evaluator.env, Counter()
    for action, seed in zip(batch.actions, batch.seeds, strict=True):
        env.reset(seed=int(seed) if seed >= 0 else fallback_seed, options=config.task.options())
        info = env.step(np.asarray(action, dtype=np.float32))[4]
        counts[str(info.get("invalid_reason") or "unknown")] += 1
    return dict(counts.most_common())


class ProgressBar(Callback):
    """A tqdm progress bar over the updates, with the best validation return.

    Args:
        disable: show nothing (the default set's bar is disabled unless ``train(progress=True)``).
    """

    def __init__(self, disable: bool = False) -> None:
        self.disable = disable
        self.bar: Any = None

    def on_training_start(self, state: TrainingState) -> None:
        self.bar = tqdm(total=state.config.updates, initial=state.update, disable=self.disable,
                        desc=state.config.agent, unit="update")

    def on_update(self, state: TrainingState) -> None:
        if self.bar is None or state.batch is None:
            return
        self.bar.update(1)
        if state.best is not None:
            self.bar.set_postfix(ret=f"{state.best['eval_return_mean']:.3g}")

    def on_training_end(self, state: TrainingState) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None


def default_callbacks(progress: bool = False) -> list[Callback]:
    """The callbacks every run gets, in their order (see the module docstring); ``progress``: show the bar."""
    return [EvaluateCallback(), BestPolicyCallback(), LogCallback(), CheckpointCallback(), FirstUpdateGuard(),
            ProgressBar(disable=not progress)]


def merge_callbacks(defaults: Sequence[Callback], given: Iterable[Callback] | None) -> CallbackList:
    """``defaults`` with each one replaced by the first of ``given`` that is an instance of its class, then the
    rest of ``given`` in their order."""
    rest, chosen = list(given or ()), []
    for default in defaults:
        found = next((index for index, callback in enumerate(rest) if isinstance(callback, type(default))), None)
        chosen.append(default if found is None else rest.pop(found))
    return CallbackList([*chosen, *rest])
