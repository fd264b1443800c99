"""Gymnasium's registered specs, looked up by an id as ``gym.make`` takes it (also ``"module:id"``)."""

from __future__ import annotations

import importlib

import gymnasium as gym

__all__ = ["find_spec"]


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
