"""Smooth actions for the stable-baselines3 learners: their policy acts on a latent vector ``z``, the env gets
``a = clip(A z, -1, 1)``.

SB3's policies are independent (diagonal) Gaussians, so exploring the DMP weights directly is white noise
along the movement, and a mean learned from it is as rough. Here ``A`` is the symmetric square root of the smooth
correlation of neighbouring weights (:func:`.learners.smooth_exploration.smooth_factor`), each column a smooth
bump, so that the learned mean ``A z`` is smooth whatever ``z`` is, with every row scaled to unit norm: noise of
standard deviation ``sigma`` on ``z`` is executed as noise of standard deviation ``sigma`` on every action
dimension (as without ``A``), correlated over about ``length`` neighbouring weights of each degree of freedom.
Single parameters (initial conditions, amplitude factors, ``approach``, ``sweep_*``) keep identity rows.
``z = 0`` (the imitation) is ``a = 0``; ``A`` is invertible, so a start action ``a0`` is ``z0 = A⁻¹ a0``. The
latent box is the action box ``[-1, 1]``: every action dimension reaches its faces, but a rough action needs
a latent beyond the box (the map leaves out mostly jagged paths).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from stable_baselines3.common.vec_env import VecEnv, VecEnvWrapper
from stable_baselines3.common.vec_env.base_vec_env import VecEnvStepReturn

from .learners.contextual import action_layout
from .learners.smooth_exploration import smooth_factor

__all__ = ["SmoothActionVecEnv", "SmoothActions"]


class SmoothActions:
    """The fixed map ``a = clip(A z, -1, 1)`` of latent actions to env actions.

    Args:
        matrix: ``[n, n]`` the invertible map ``A``.
    """

    def __init__(self, matrix: np.ndarray) -> None:
        matrix = np.asarray(matrix, dtype=np.float64)
        if matrix.ndim != 2 or matrix.shape[0] != matrix.shape[1] or not np.all(np.isfinite(matrix)):
            raise ValueError(f"matrix: expected a finite square matrix, got shape {matrix.shape}")
        self.matrix = matrix

    @classmethod
    def from_env(cls, env: Any, length: float) -> SmoothActions:
        """The map for ``env``'s action layout (:func:`.learners.contextual.action_layout`), correlated over
        ``length`` (> 0) neighbouring weights, each row of ``A`` of unit norm."""
        slices, n_dims = action_layout(env)
        factor = smooth_factor(int(env.action_space.shape[0]), slices, n_dims, length, symmetric=True)
        return cls(factor / np.linalg.norm(factor, axis=1, keepdims=True))

    def __call__(self, latent: np.ndarray) -> np.ndarray:
        """``[..., n]`` env actions in ``[-1, 1]`` of latent actions ``[..., n]``."""
        return np.clip(np.asarray(latent, dtype=np.float64) @ self.matrix.T, -1.0, 1.0)

    def latent(self, action: np.ndarray) -> np.ndarray:
        """``[n]`` the latent ``z = A⁻¹ a`` of an action ``a [n]`` (exact for ``a`` in the box)."""
        return np.linalg.solve(self.matrix, np.asarray(action, dtype=np.float64))


class SmoothActionVecEnv(VecEnvWrapper):
    """A vector env whose actions are latent: each step executes ``actions(z)`` (:class:`SmoothActions`)."""

    def __init__(self, venv: VecEnv, actions: SmoothActions) -> None:
        super().__init__(venv)
        self.actions = actions

    def step_async(self, actions: np.ndarray) -> None:
        self.venv.step_async(self.actions(actions))

    def step_wait(self) -> VecEnvStepReturn:
        return self.venv.step_wait()

    def reset(self) -> Any:
        return self.venv.reset()
