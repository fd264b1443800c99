"""``rdmp_gym/ArmarWipe-v0``: the deprecated id, which makes ``rdmp_gym/ArmarWipe-v1`` without the cup."""

from __future__ import annotations

import warnings
from typing import Any

from ..env import ArmarWipeEnv

__all__ = ["deprecated_v0"]


def deprecated_v0(**kwargs: Any) -> ArmarWipeEnv:
    """Entry point of the deprecated ``rdmp_gym/ArmarWipe-v0``: warns and makes v1 without the obstacle.

    v0's reward counted dirt beyond the table edge, touching as wiping and let the arm pass through the
    robot; v1 (:class:`~rdmp_gym.envs.tasks.wiping.env.ArmarWipeEnv`) fixes all of it and changes the reward's
    meaning, hence the new version.
    """
    warnings.warn("rdmp_gym/ArmarWipe-v0 is deprecated and will be removed: its reward could be gamed. It now "
                  "makes rdmp_gym/ArmarWipe-v1 with obstacle=False; use rdmp_gym/ArmarWipe-v3, the current task.",
                  DeprecationWarning, stacklevel=2)
    kwargs.setdefault("obstacle", False)
    kwargs.setdefault("version", 1)
    return ArmarWipeEnv(**kwargs)
