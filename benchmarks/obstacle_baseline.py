"""The no-learning obstacle baseline for the wiping env: the imitation DMP with an obstacle coupling term,
integrated online in the :class:`~rdmp_gym.DMPStepper` and run through ``env.run_path``.

:func:`coupling_baseline_scores` is the baseline of the agents table: on ArmarWipe-v1 it lifts the approach
over the episode's cup (:class:`~rdmp_gym.dmp.coupling.LiftOver`: the cup as a cylinder, its radius inflated by the
sponge's half diagonal, the lift gated to the approach; :class:`~rdmp_gym.dmp.coupling.AdaptiveLift`: only as far as
the free approach needs) and runs the plain imitation where there is no cup.
The planar steering term of Hoffmann et al. (:func:`run_avoiding`, a point obstacle on the sponge's centre in
the table plane) does not avoid the cup: the sponge and the hand are wider than the detour (see
``benchmarks/bench_obstacle.py``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from rdmp_gym.envs.tasks.wiping.approach import LIFT_PROFILE
from rdmp_gym.envs.tasks.wiping.scene import TablePose, control_frame, table_frame

from rdmp_gym.dmp.coupling import AdaptiveLift, LiftOver, ObstacleAvoidance, avoiding_rollout, spring_stiffness
from rdmp_gym.synthetic.smoothness import integrated_squared_jerk

__all__ = ["avoiding_path", "coupling_baseline_scores", "cup_in_path_frame", "cup_position", "lift_term",
           "lifting_path", "path_jerk_ratio", "run_avoiding", "run_lifting"]

#: Horizontal margin (m) added to the sponge's half diagonal: the hand above it and the sponge's tilt in the air.
REACH_MARGIN = 0.01


def cup_position(env) -> np.ndarray | None:
    """The cup's centre ``[2]`` (table frame, m) in the env's current context, or ``None`` without a cup."""
    context = env.unwrapped.context
    if context is None:
        raise RuntimeError("call reset() before cup_position()")
    return np.array(context.obstacle_position, dtype=np.float64) if context.obstacle else None


def cup_in_path_frame(env) -> tuple[np.ndarray, float] | None:
    """(centre ``[2]`` (m), height of its top (m)) of the episode's cup in the frame the env's paths live in (the
    nominal table origin, the actual tilt: :func:`~rdmp_gym.envs.tasks.wiping.scene.control_frame`), or ``None``
    without a cup. The cup stands on the actual table, which the context shifts by ``table_height`` (observation
    field 0)."""
    xy = cup_position(env)
    if xy is None:
        return None
    parts, pose = env.unwrapped.task.parts, TablePose.of(env.unwrapped.context)
    origin, rot = table_frame(parts, pose)
    control_origin, control_rot = control_frame(parts, pose)
    base = control_rot.T @ (origin + rot @ np.r_[xy, 0.0] - control_origin)
    top = base[2] + 2.0 * parts.obstacle_half_height
    return base[:2], float(top)


def lift_term(env, clearance: float = 0.02, ramp: float = 0.15, profile: tuple[float, float, float] = LIFT_PROFILE
              ) -> LiftOver | None:
    """The :class:`LiftOver` term of the episode's cup (``None`` without one): the cup's radius and top in the
    path frame, the sponge's half diagonal plus :data:`REACH_MARGIN` as the reach, the DMP's spring, and the
    gate ``profile`` (rise, hold, release as fractions of the transient: the approach, as the env's ``approach``
    action dimension)."""
    cup = cup_in_path_frame(env)
    if cup is None:
        return None
    inner = env.unwrapped
    centre, top = cup
    half = inner.task.parts.sponge_half
    length = inner.dmp.transients[0].length
    return LiftOver(centre, top, inner.task.parts.obstacle_radius, float(np.hypot(half[1], half[2])) + REACH_MARGIN,
                    spring_stiffness(inner.dmp), clearance=clearance, ramp=ramp,
                    window=tuple(fraction * length for fraction in profile))


def _online_path(env, terms: list, substeps: int, smoothing: float = 0.0) -> np.ndarray:
    """The imitation integrated online with coupling ``terms`` at ``substeps`` x the control rate, ``[T_ctrl, 3]``
    (anchored at the patch centre, started at the sponge with ``start_blend``, as ``rollout_path``)."""
    inner = env.unwrapped
    if isinstance(substeps, bool) or not isinstance(substeps, (int, np.integer)) or substeps < 1:
        raise ValueError(f"substeps: expected an int >= 1, got {substeps!r}")
    anchor = np.array([*inner.context.patch_centre, inner.task._anchor_z])
    fine = np.arange((inner.n_steps - 1) * substeps + 1) * (inner.dt / substeps)
    dmp = inner.policy_dmp(inner.action_map.theta0)
    path, _ = avoiding_rollout(dmp, fine, terms, smoothing=smoothing, y0=inner.context.sponge_start, anchor=anchor,
                               start_blend=True)
    return path[::substeps]


def lifting_path(env, substeps: int = 5, adaptive: bool = True, lead: float = 0.3, **term_kwargs: Any
                 ) -> np.ndarray:
    """Sponge path ``[T_ctrl, 3]`` (path frame) of the imitation lifted over the episode's cup, integrated online:
    by :class:`~rdmp_gym.dmp.coupling.AdaptiveLift` (``lead`` s) of :func:`lift_term` (``term_kwargs``), or with
    ``adaptive=False`` by the conservative :class:`~rdmp_gym.dmp.coupling.LiftOver` itself (the full height everywhere
    over the footprint); the plain imitation (``rollout_path``) without a cup."""
    inner = env.unwrapped
    if inner.context is None:
        raise RuntimeError("call reset() before lifting_path()")
    term = lift_term(env, **term_kwargs)
    if term is None:
        return inner.rollout_path(inner.action_map.theta0)
    return _online_path(env, [AdaptiveLift(term, lead) if adaptive else term], substeps)


def path_jerk_ratio(env, path: np.ndarray) -> float:
    """Integrated squared jerk of ``path [T_ctrl, 3]`` over the imitation's in the current context (as
    ``rdmp_gym.agents.protocol.path_jerk``: third differences of the commanded path at the control rate)."""
    inner = env.unwrapped
    imitation = integrated_squared_jerk(inner.rollout_path(inner.action_map.theta0), inner.dt)
    return integrated_squared_jerk(path, inner.dt) / max(imitation, 1e-300)


def run_lifting(env, **kwargs: Any) -> tuple[float, dict]:
    """Run :func:`lifting_path` in the env's current context; returns ``(reward, info)`` with, where there is a
    cup, ``info["obstacle_clearance"]``: the smallest :meth:`LiftOver.clearance_of` along the path (m; > 0: the
    sponge's disc passes beside or above the cup)."""
    path = lifting_path(env, **kwargs)
    reward, info = env.unwrapped.run_path(path)
    term = lift_term(env, **{k: v for k, v in kwargs.items() if k not in ("substeps", "adaptive", "lead")})
    if term is not None:
        info["obstacle_clearance"] = float(np.min(term.clearance_of(path)))
    info["path_jerk_ratio"] = path_jerk_ratio(env, path)
    return reward, info


def coupling_baseline_scores(env, seeds: np.ndarray, options: dict[str, Any] | None = None,
                             **kwargs: Any) -> dict[str, np.ndarray]:
    """The no-learning coupling baseline on the reset seeds ``seeds [E]`` (each context exactly as
    ``env.reset(seed=s, options=options)`` draws it): :func:`run_lifting` in each.

    Returns per-context arrays ``[E]``: ``seeds``, ``returns``, ``coverage``, ``force_in_band_fraction``, ``valid``,
    ``success`` (``info["is_success"]``), ``jerk_ratio`` (integrated squared jerk of the commanded path over the
    imitation's), ``cup`` (the context has one), ``cup_touched`` (the arm touched it), ``cup_shift`` (m),
    ``peak_joint_accel`` (rad/s^2, of the planned joint path; NaN for an invalid path).
    """
    seeds = np.asarray(seeds)
    if seeds.ndim != 1 or seeds.size == 0 or not np.issubdtype(seeds.dtype, np.integer):
        raise ValueError(f"seeds: expected a non-empty 1-D array of integer reset seeds, got {seeds!r}")
    rows = []
    for seed in seeds:
        env.reset(seed=int(seed), options=None if options is None else dict(options))
        reward, info = run_lifting(env, **kwargs)
        rows.append((reward, info["coverage"], info["force_in_band_fraction"], info["valid"], info["is_success"],
                     info["path_jerk_ratio"], env.unwrapped.context.obstacle, info["obstacle_touch_steps"] > 0,
                     info["obstacle_shift"], info["peak_joint_accel"]))
    columns = list(zip(*rows, strict=True))
    names = ("returns", "coverage", "force_in_band_fraction", "valid", "success", "jerk_ratio", "cup", "cup_touched",
             "cup_shift", "peak_joint_accel")
    kinds = (np.float64, np.float64, np.float64, bool, bool, np.float64, bool, bool, np.float64, np.float64)
    out = {"seeds": seeds.astype(np.int64)}
    out.update({name: np.asarray(column, dtype=kind) for name, column, kind in zip(names, columns, kinds, strict=True)})
    return out


def avoiding_path(env, obstacle_xy: np.ndarray | None = None, gamma: float = 2e4, distance_scale: float = 0.03,
                  smoothing: float = 0.0, substeps: int = 5) -> np.ndarray:
    """Sponge path ``[T_ctrl, 3]`` (nominal table frame) of the imitation in the env's current context, steered
    in the table plane around a point obstacle at ``obstacle_xy [2]`` (m; default: the context's cup; the plain
    imitation when there is none) by Hoffmann et al.'s term; ``gamma``, ``distance_scale`` and ``smoothing`` as
    in :class:`~rdmp_gym.dmp.coupling.ObstacleAvoidance` and :func:`~rdmp_gym.dmp.coupling.avoiding_rollout`."""
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
    term = ObstacleAvoidance(obstacle_xy, gamma=gamma, distance_scale=distance_scale, dims=(0, 1))
    return _online_path(env, [term], substeps, smoothing)


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
