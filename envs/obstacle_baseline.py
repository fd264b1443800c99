"""The no-learning obstacle baseline for the wiping env: the imitation DMP with the obstacle-avoidance coupling
term (:mod:`rdmp_gym.coupling`, Hoffmann et al. 2009) in the table plane, run through ``env.run_path``.

The agents benchmark calls :func:`run_avoiding` with the obstacle's position in the nominal table frame; the
learners must beat it. Until the env models the obstacle itself, its reward carries no collision term, so
the clearance (``info["obstacle_clearance"]``) is reported beside it.
"""

from __future__ import annotations

import numpy as np

from rdmp_gym.coupling import ObstacleAvoidance, avoiding_rollout

__all__ = ["avoiding_path", "run_avoiding"]


def avoiding_path(env, obstacle_xy: np.ndarray, gamma: float = 2e4, distance_scale: float = 0.03,
                  smoothing: float = 0.0, substeps: int = 5) -> np.ndarray:
    """Sponge path ``[T_ctrl, 3]`` (nominal table frame) of the imitation in the env's current context, steered
    around a point obstacle at ``obstacle_xy [2]`` on the table (m). The DMP is integrated online at
    ``substeps`` times the control rate (as :meth:`ArmarWipeEnv.rollout_path`: anchored at the patch centre,
    started at the sponge with ``start_blend``); ``gamma``, ``distance_scale`` and ``smoothing`` as in
    :class:`~rdmp_gym.coupling.ObstacleAvoidance` and :func:`~rdmp_gym.coupling.avoiding_rollout`."""
    inner = env.unwrapped
    if inner.context is None:
        raise RuntimeError("call reset() before avoiding_path()")
    obstacle_xy = np.asarray(obstacle_xy, dtype=np.float64)
    if obstacle_xy.shape != (2,) or not np.all(np.isfinite(obstacle_xy)):
        raise ValueError(f"obstacle_xy: expected 2 finite numbers, got {obstacle_xy!r}")
    if int(substeps) < 1:
        raise ValueError(f"substeps: expected an int >= 1, got {substeps!r}")
    anchor = np.array([*inner.context.patch_centre, inner._anchor_z])
    fine = np.arange((inner.n_steps - 1) * int(substeps) + 1) * (inner.dt / int(substeps))
    term = ObstacleAvoidance(obstacle_xy, gamma=gamma, distance_scale=distance_scale, dims=(0, 1))
    dmp = inner.dmp.with_params(inner.action_map.theta0, inner.groups)
    path, _ = avoiding_rollout(dmp, fine, term, smoothing=smoothing, y0=inner.context.sponge_start, anchor=anchor,
                               start_blend=True)
    return path[:: int(substeps)]


def run_avoiding(env, obstacle_xy: np.ndarray, **kwargs) -> tuple[float, dict]:
    """Run :func:`avoiding_path` in the env's current context; returns ``(reward, info)`` with
    ``info["obstacle_clearance"]``: the smallest distance (m) of the path's table-plane trace to the obstacle."""
    path = avoiding_path(env, obstacle_xy, **kwargs)
    reward, info = env.unwrapped.run_path(path)
    info["obstacle_clearance"] = float(np.min(np.linalg.norm(path[:, :2] - np.asarray(obstacle_xy), axis=1)))
    return reward, info
