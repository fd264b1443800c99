"""The agents a run can train, each declared by its own module with :func:`register`.

A learner module declares its name, its settings class and what builds it::

    register("pi2", PI2Config, PI2)                                        # an ask/tell learner
    register("bbrl", BBRLConfig, "rdmp_gym.agents.learners.bbrl:BBRL", uses_context=True)
    register("ppo", PPOConfig, "rdmp_gym.agents.sb3:PPOAgent", kind="sb3")

A target given as ``"module:Class"`` is imported only when the agent is built, so that declaring a learner
that needs torch (``bbrl``, PPO, SAC) does not import torch. An ask/tell learner (``kind="learner"``) is built
by its class's ``build`` (:class:`rdmp_gym.agents.learners.Learner`); an SB3 agent by its ``from_run``.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Any

from .config import Settings

__all__ = ["REGISTRY", "AgentSpec", "agent_spec", "register"]

KINDS = ("learner", "sb3")


@dataclass(frozen=True)
class AgentSpec:
    """One registered agent.

    Attributes:
        name: the name runs and the command line use (``--agent``).
        config: its settings (a :class:`~rdmp_gym.agents.config.Settings` subclass).
        target: the class that builds it, or ``"module:Class"`` to import on first use.
        kind: ``"learner"`` (ask/tell, run by the training loop's episodes) or ``"sb3"`` (runs its own envs).
        uses_context: its policy depends on the context (it needs the action layout and context standardisation).
    """

    name: str
    config: type[Settings]
    target: type | str
    kind: str = "learner"
    uses_context: bool = False

    def load(self) -> Any:
        """The class that builds the agent (importing its module if it was declared by name)."""
        if not isinstance(self.target, str):
            return self.target
        module, _, name = self.target.partition(":")
        return getattr(importlib.import_module(module), name)


#: name -> :class:`AgentSpec`, in the order the agents were declared
REGISTRY: dict[str, AgentSpec] = {}


def register(name: str, config: type[Settings], target: type | str, *, kind: str = "learner",
             uses_context: bool | None = None) -> AgentSpec:
    """Declare an agent; ``uses_context`` defaults to the target class's ``uses_context`` (False for a name)."""
    if kind not in KINDS:
        raise ValueError(f"kind: expected one of {list(KINDS)}, got {kind!r}")
    if not (isinstance(config, type) and issubclass(config, Settings)):
        raise TypeError(f"config: expected a Settings subclass, got {config!r}")
    if uses_context is None:
        uses_context = bool(getattr(target, "uses_context", False))
    spec = AgentSpec(name, config, target, kind, uses_context)
    if REGISTRY.get(name, spec) != spec:
        raise ValueError(f"name: an agent {name!r} is already registered ({REGISTRY[name]})")
    REGISTRY[name] = spec
    return spec


def agent_spec(name: str) -> AgentSpec:
    """The registered agent ``name`` (a ``ValueError`` naming the choices otherwise)."""
    if name not in REGISTRY:
        raise ValueError(f"agent: expected one of {sorted(REGISTRY)}, got {name!r}")
    return REGISTRY[name]
