"""A training run's configuration (:class:`TrainConfig`, stored as ``config.json``) and what the training loop
needs from an agent (:class:`Agent`).

The loop (:mod:`rdmp_gym.agents.training`) and its callbacks (:mod:`rdmp_gym.agents.callbacks`) both read them;
``from rdmp_gym.agents.training import TrainConfig`` keeps working.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any, Literal, Protocol

import numpy as np
from rdmp_gym.envs.registration import env_settings

from rdmp_gym.validation import check_choice, check_range

from . import sb3_config  # noqa: F401  (declares PPO and SAC)
from .config import Settings
from .learners import CONTEXTUAL, EpisodeBatch
from .registry import REGISTRY, agent_spec
from .tasks import MAIN_ENV, TaskSpec, main_agent, main_env_kwargs, main_options, task_options

__all__ = ["AGENTS", "START_MODES", "Agent", "AgentName", "StartMode", "TrainConfig"]

#: every registered agent's name (the ask/tell learners, ``ppo`` and ``sac``)
AGENTS = tuple(REGISTRY)
START_MODES = ("imitation", "perturbed", "shrunk")
_SEED_LIMIT = 2**31 - 1


#: an agent's name as a type (the command line's choices)
AgentName = Literal[AGENTS]  # type: ignore[valid-type]
#: a start mode's name as a type
StartMode = Literal[START_MODES]  # type: ignore[valid-type]


@dataclass(frozen=True)
class TrainConfig:
    """Everything that defines a training run (stored as ``config.json``).

    Each attribute's first sentence is the help of its ``rdmp-gym train`` flag, which is derived from this class
    (:mod:`rdmp_gym.agents.run_commands`).

    Attributes:
        agent: the learner (None: the env's default, bbrl on an episodic env and cmaes on a step-based one). One
            of ``rdmp_gym.agents.learners.LEARNERS`` (``bbrl``, ``creps``, ``cpibb``, ``cpi2``, ``pi2``, ``cmaes``,
            the baselines ``amplitude`` and ``random``), ``ppo`` or ``sac``; the defaults are
            :func:`~rdmp_gym.agents.tasks.main_agent`'s.
        updates: number of updates.
        rollouts: training episodes per update.
        seed: run seed.
        workers: worker processes (or Ray actors) for the episodes (the numbers do not depend on it). PPO's parallel
            envs are its own setting ``envs``.
        env_id: the env: a registered id with a continuous action space, episodic or step-based. An episodic env
            (one that declares a task contract, :func:`rdmp_gym.envs.specs.is_episodic`) runs as it is, a step-based
            one under the rhythmic black-box wrapper; default the current task
            (:data:`~rdmp_gym.agents.tasks.MAIN_ENV`).
        env_kwargs: the env's settings, validated once against the env (:attr:`env_settings`; an unknown or bad setting
            is an error naming it): the wiping task's ``style``, ``groups``, ``n_periodic``, ``duration``, ...; on a
            step-based env the wrapper's settings (``p_gains``, ``groups``, ``duration``, ...) and the env's
            ``gym.make`` keywords (:func:`rdmp_gym.envs.blackbox.split_settings`). None: the main job's keywords on its
            env, else none (:func:`~rdmp_gym.agents.tasks.main_env_kwargs`).
        reset_options: options for every reset (e.g. a fixed context), or None.
        options: the agent's settings: its typed settings object (``PI2Config``, ``BBRLConfig``, ``PPOConfig``, ...,
            used as given), or a mapping of their fields over the task's defaults for the agent
            (``tasks.task_options``: e.g. a contextual search on the wiping task starts from the task's learner
            defaults, ``rdmp_gym.envs.registration.learner_defaults``); None: the main job's options for the main
            learner on its env, else none (:func:`~rdmp_gym.agents.tasks.main_options`). Stored as the typed object.
        start: the start of the search. ``imitation`` (the fitted DMP, ``a = 0``), ``perturbed`` (plus Gaussian noise
            of std ``perturbation`` in action units) or ``shrunk`` (the DMP weights scaled by ``1 - perturbation``: a
            smaller, damped movement; the initial conditions as fitted).
        perturbation: size of the perturbed or shrunk start.
        demo: a CSV/NPZ demonstration for the env to fit its initial DMP to ("" = none). In the env's own space: the
            wiping and tracking tasks' table frame in metres, a step-based env's actuated joints; given to the env (or
            the wrapper) as its ``demonstration`` keyword, refused by an env that takes none.
        eval_episodes: validation contexts the policy is evaluated on after every ``eval_every`` updates (fixed
            seeds).
        eval_every: updates between policy evaluations (and after the last one).
        shared_context: all rollouts of one update share one context (None: not for the contextual learners, which
            always get one context per rollout, else yes). The contextual learners are ``bbrl``, ``creps``,
            ``cpibb``, ``cpi2``, ``amplitude`` and ``random``; the same episodes either way.
        stratified_validation: spread the validation contexts evenly over the kinds of context the env names,
            instead of taking the first ``eval_episodes`` seeds. See
            :func:`~rdmp_gym.agents.protocol.stratified_validation_seeds`; e.g. the wiping task's cup on the approach,
            cup beside the patch, largest patch, no cup.
    """

    agent: AgentName | None = None
    updates: int = 30
    rollouts: int = 10
    seed: int = 0
    workers: int = 1
    env_id: str = MAIN_ENV
    env_kwargs: Mapping[str, Any] | None = None
    reset_options: dict[str, Any] | None = None
    options: Settings | Mapping[str, Any] | None = None
    start: StartMode = "imitation"
    perturbation: float = 0.3
    demo: str = ""
    eval_episodes: int = 1
    shared_context: bool | None = None
    stratified_validation: bool = False
    eval_every: int = 1

    def __post_init__(self) -> None:
        if self.agent is None:
            object.__setattr__(self, "agent", main_agent(self.env_id))
        check_choice(self.agent, "agent", AGENTS)
        check_range(self.updates, "updates", 1, None)
        check_range(self.rollouts, "rollouts", 2, None)
        check_range(self.seed, "seed", 0, _SEED_LIMIT)
        check_range(self.workers, "workers", 1, None)
        check_range(self.perturbation, "perturbation", 0.0, 1.0)
        check_range(self.eval_episodes, "eval_episodes", 1, None)
        check_range(self.eval_every, "eval_every", 1, None)
        check_choice(self.start, "start", START_MODES)
        if self.env_kwargs is None:
            object.__setattr__(self, "env_kwargs", main_env_kwargs(self.env_id))
        if not isinstance(self.env_kwargs, Mapping):
            raise TypeError(f"env_kwargs: expected a mapping, got {type(self.env_kwargs).__name__}")
        env_settings(self.env_id, self.env_kwargs)
        if self.demo:
            try:
                env_settings(self.env_id, {**self.env_kwargs, "demonstration": None})
            except (TypeError, ValueError) as error:
                raise ValueError(f"demo: {self.env_id} takes no demonstration ({error})") from None
        if self.options is None:
            object.__setattr__(self, "options", main_options(self.agent, self.env_id))
        if self.shared_context is None:
            object.__setattr__(self, "shared_context", self.agent not in CONTEXTUAL)
        if self.reset_options is not None and not isinstance(self.reset_options, Mapping):
            raise TypeError(f"reset_options: expected a mapping or None, got {type(self.reset_options).__name__}")
        settings = agent_spec(self.agent).config
        if isinstance(self.options, Mapping):
            merged = task_options(self.env_id, self.agent, self.options, self.env_kwargs)
            object.__setattr__(self, "options", settings.from_dict(merged, self.agent))
        elif type(self.options) is not settings:
            raise TypeError(f"options: expected {settings.__name__} or a mapping for {self.agent}, "
                            f"got {type(self.options).__name__}")

    @classmethod
    def from_dict(cls, values: Mapping[str, Any]) -> TrainConfig:
        """Build from a mapping (e.g. ``config.json``, also as earlier versions wrote it); unknown keys are a
        ``ValueError``, values of the wrong type a ``TypeError`` naming the field."""
        values = dict(values)
        known = {item.name for item in fields(cls)}
        unknown = sorted(set(values) - known)
        if unknown:
            raise ValueError(f"config: unknown option(s) {unknown}; expected some of {sorted(known)}")
        for name, kind in (("agent", str), ("env_id", str), ("start", str), ("demo", str), ("shared_context", bool),
                           ("stratified_validation", bool)):
            if name in values and not isinstance(values[name], kind):
                raise TypeError(f"config.{name}: expected {kind.__name__}, got {values[name]!r}")
        for name in ("updates", "rollouts", "seed", "workers", "eval_episodes", "eval_every"):
            if name in values and (isinstance(values[name], bool) or not isinstance(values[name], int)):
                raise TypeError(f"config.{name}: expected an integer, got {values[name]!r}")
        if isinstance(values.get("options", {}), Mapping):
            spec = agent_spec(values.get("agent") or main_agent(values.get("env_id", MAIN_ENV)))
            values["options"] = spec.config.from_dict(values.get("options"), spec.name)
        return cls(**values)

    def to_dict(self) -> dict[str, Any]:
        """JSON-friendly fields (the options as a JSON object)."""
        values = {item.name: getattr(self, item.name) for item in fields(self)}
        return {**values, "env_kwargs": dict(self.env_kwargs), "options": self.options.to_dict(),
                "reset_options": None if self.reset_options is None else dict(self.reset_options)}

    @property
    def env_settings(self) -> Any:
        """The env's typed, validated settings (:func:`rdmp_gym.envs.registration.env_settings`: the wiping task's
        :class:`~rdmp_gym.envs.tasks.wiping.settings.EnvConfig`, else its keywords)."""
        return env_settings(self.env_id, self.env_kwargs)

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
