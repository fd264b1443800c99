"""The no-learning obstacle baseline for the wiping env: the imitation DMP with the obstacle-avoidance coupling
term (:mod:`rdmp_gym.coupling`, Hoffmann et al. 2009) in the table plane, run through ``env.run_path``.

The agents benchmark calls :func:`run_avoiding` after ``reset``: by default the obstacle is the episode's cup
(ArmarWipe-v1's context, observation fields 10-12, table frame); without a cup it runs the imitation. The
learners must beat it. The steering acts on the sponge's path only (a point obstacle at the cup's centre in
the table plane); the arm above the sponge is not steered (see ``benchmarks/bench_obstacle.py``).
"""

from __future__ import annotations

import numpy as np

from rdmp_gym.coupling import ObstacleAvoidance, avoiding_rollout

__all__ = ["avoiding_path", "cup_position", "run_avoiding"]


def avoiding_path(env, obstacle_xy: np.ndarray | None = None, gamma: float = 2e4, distance_scale: float = 0.03,
                  smoothing: float = 0.0, substeps: int = 5) -> np.ndarray:
    """Sponge path ``[T_ctrl, 3]`` (nominal table frame) of the imitation in the env's current context, steered
    around a point obstacle at ``obstacle_xy [2]`` on the table (m; default: the context's cup; the plain
    imitation when there is none). The DMP is integrated online at
    ``substeps`` times the control rate (as :meth:`ArmarWipeEnv.rollout_path`: anchored at the patch centre,
    started at the sponge with ``start_blend``); ``gamma``, ``distance_scale`` and ``smoothing`` as in
    :class:`~rdmp_gym.coupling.ObstacleAvoidance` and :func:`~rdmp_gym.coupling.avoiding_rollout`."""
    inner = env.unwrapped
    if inner.context is None:
        raise RuntimeError("call reset() before avoiding_path()")
    if obstacle_xy is None:
        obstacle_xy = cup_position(env)
        if obstacle_xy is None:
            return inner.rollout_path(inner.action_map.theta0)
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


def cup_position(env) -> np.ndarray | None:
    """The cup's centre ``[2]`` (table frame, m) in the env's current context, or ``None`` without a cup."""
    context = env.unwrapped.context
    if context is None:
        raise RuntimeError("call reset() before cup_position()")
    return np.array(context.obstacle_position, dtype=np.float64) if context.obstacle else None


def run_avoiding(env, obstacle_xy: np.ndarray | None = None, **kwargs) -> tuple[float, dict]:
    """Run :func:`avoiding_path` in the env's current context (default obstacle: its cup); returns
    ``(reward, info)``, with ``info["obstacle_clearance"]`` where there is an obstacle: the smallest distance (m)
    of the path's table-plane trace to it."""
    path = avoiding_path(env, obstacle_xy, **kwargs)
    reward, info = env.unwrapped.run_path(path)
    obstacle = cup_position(env) if obstacle_xy is None else np.asarray(obstacle_xy, dtype=np.float64)
    if obstacle is not None:
        info["obstacle_clearance"] = float(np.min(np.linalg.norm(path[:, :2] - obstacle, axis=1)))
    return reward, info
