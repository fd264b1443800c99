"""Gymnasium's registered specs, looked up by an id as ``gym.make`` takes it (also ``"module:id"``), and what the env
of an id is: episodic (it declares a task contract, :mod:`rdmp_gym.envs.contract`) or step-based."""

from __future__ import annotations

import importlib
import inspect
import typing
from collections.abc import Callable
from typing import Any

import gymnasium as gym

__all__ = ["declares_contract", "env_class", "env_creator", "find_spec", "is_episodic"]


def find_spec(env_id: str) -> gym.envs.registration.EnvSpec:
    """The registered spec of ``env_id``, also in the ``"module:id"`` form ``gym.make`` takes (the module is imported
    first: it registers the id). Raises ValueError naming ``env_id`` for an id nobody registers."""
    module, _, name = env_id.rpartition(":")
    try:
        if module:
            importlib.import_module(module)
        return gym.spec(name)
    except (gym.error.Error, ModuleNotFoundError) as error:
        raise ValueError(f"env_id: no env registered as {env_id!r} ({error})") from None


def env_creator(env_id: str) -> Callable[..., Any]:
    """What ``gym.make(env_id)`` calls: the spec's entry point, a class or a function (a ``"module:name"`` string
    loaded)."""
    entry = find_spec(env_id).entry_point
    if entry is None:
        raise ValueError(f"env_id: {env_id!r} is registered without an entry point")
    return gym.envs.registration.load_env_creator(entry) if isinstance(entry, str) else entry


def env_class(env_id: str) -> type | None:
    """The class of the env ``gym.make(env_id)`` builds (its ``unwrapped``), told without building it: the entry
    point where it is a class, else the class its return annotation names; None where neither tells."""
    creator = env_creator(env_id)
    if inspect.isclass(creator):
        return creator
    try:
        returned = typing.get_type_hints(creator).get("return")
    except Exception:                   # an annotation that does not resolve tells nothing
        return None
    return returned if inspect.isclass(returned) and issubclass(returned, gym.Env) else None


def declares_contract(kind: type) -> bool:
    """Whether envs of the class ``kind`` declare a task contract (``task_contract()``, :mod:`rdmp_gym.envs.contract`):
    the episodic envs (one step = one DMP rollout), which the agents run as they are."""
    return callable(getattr(kind, "task_contract", None))


def is_episodic(env_id: str) -> bool:
    """Whether the env of ``env_id`` is episodic (declares a task contract) rather than step-based (which the agents
    run under the rhythmic black-box wrapper): by its class (:func:`env_class`), or, where its entry point does not
    tell, by building it once with its registered keywords.

    Raises:
        ValueError: an unknown id, or one that neither tells its class nor builds without keywords.
    """
    kind = env_class(env_id)
    if kind is not None:
        return declares_contract(kind)
    try:
        env = gym.make(env_id, disable_env_checker=True)
    except Exception as error:          # any failure of a foreign env's constructor
        raise ValueError(f"env_id: cannot tell whether {env_id} is episodic: its entry point names no env class and "
                         f"building it without keywords failed ({type(error).__name__}: {error}); register it with "
                         f"its class as the entry point (or a function annotated to return it)") from error
    try:
        return declares_contract(type(env.unwrapped))
    finally:
        env.close()
