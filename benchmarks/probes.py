"""Hand-made sponge paths that try to game the wiping reward (for tests and ``benchmarks/bench_env.py``).

Each path function returns a path ``[T, 3]`` in the table frame for :meth:`ArmarWipeEnv.run_path`, built in
the env's current context. They keep the imitation's approach (so the touchdown is the same) and then
do something cheap instead of wiping: hold still, press and lift on a grid, reach into the robot.
(The honest counterpart for the cup, a raised approach, is an action: the env's ``approach`` dimension.)
"""

from __future__ import annotations

import numpy as np
from rdmp_gym.envs.tasks.wiping.env import ArmarWipeEnv

__all__ = ["hold_still", "into_the_torso", "press_lift_grid", "wiping_force_at_500hz"]


def _smooth(x: np.ndarray) -> np.ndarray:
    """Smoothstep of ``x`` clipped to [0, 1]."""
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


def _imitation(env: ArmarWipeEnv) -> np.ndarray:
    return env.rollout_path(env.action_map.theta0)


def _blend(path: np.ndarray, target: np.ndarray, start: int, steps: int) -> np.ndarray:
    """``path`` from step ``start`` on moved smoothly (over ``steps``) onto ``target [T, 3]``."""
    weight = _smooth((np.arange(len(path)) - start) / max(1, steps))[:, None]
    return (1.0 - weight) * path + weight * target


def hold_still(env: ArmarWipeEnv, depth: float = 0.0) -> np.ndarray:
    """The imitation's approach, then the sponge parked on the patch centre for the whole wiping phase."""
    path = _imitation(env)
    centre = np.array([*env.context.patch_centre, -depth])
    start = int(np.argmax(env.task.periodic))
    return _blend(path, np.tile(centre, (len(path), 1)), start, round(0.3 / env.dt))


def press_lift_grid(env: ArmarWipeEnv, grid: int = 3, lift: float = 0.03) -> np.ndarray:
    """The imitation's approach, then press–hold–lift at the points of a ``grid`` x ``grid`` lattice
    over the patch (the sponge moves between points in the air)."""
    path = _imitation(env)
    start = int(np.argmax(env.task.periodic))
    count = len(path) - start
    size, centre = env.context.patch_size, env.context.patch_centre
    offsets = (np.arange(grid) + 0.5) / grid - 0.5
    points = np.array([[centre[0] + ox * size[0], centre[1] + oy * size[1]] for ox in offsets for oy in offsets])
    slot = count / len(points)
    target = np.zeros((len(path), 3))
    target[:start] = path[:start]
    for k in range(count):
        i = min(len(points) - 1, int(k / slot))
        phase = (k - i * slot) / slot                    # 0..1 within this point's slot
        previous = points[max(0, i - 1)]
        xy = previous + _smooth(phase / 0.35) * (points[i] - previous)
        press = _smooth((phase - 0.35) / 0.15) * (1.0 - _smooth((phase - 0.8) / 0.15))
        target[start + k] = [*xy, lift * (1.0 - press)]
    return _blend(path, target, start, round(0.3 / env.dt))


def into_the_torso(env: ArmarWipeEnv, point: tuple[float, float, float] = (-0.30, 0.28, 0.15)) -> np.ndarray:
    """The imitation's approach, then a smooth reach to ``point`` (table frame), inside the robot's torso
    (its front face is at x = -0.26 in the table frame, for y in [0.10, 0.46] and z above 0.05 m)."""
    path = _imitation(env)
    start = int(np.argmax(env.task.periodic))
    return _blend(path, np.tile(np.asarray(point, dtype=np.float64), (len(path), 1)), start, round(1.0 / env.dt))


def wiping_force_at_500hz(env, options: dict | None, seed: int = 0) -> tuple[np.ndarray, dict]:
    """Run the imitation (action 0) in ``env`` (a ``gym.make`` of the wiping env) with the sponge-table force
    recorded at every physics step. Returns the force ``[S]`` (N) from 0.5 s into the wiping phase on, and the
    episode's ``info`` (its ``fine_force_trace`` holds the whole episode)."""
    face = env.unwrapped
    face.task.fine_force = True
    try:
        env.reset(seed=seed, options=options)
        info = env.step(np.zeros(env.action_space.shape, dtype=np.float32))[4]
    finally:
        face.task.fine_force = False
    start = (int(np.argmax(face.task.periodic)) + round(0.5 / face.dt)) * face.frame_skip
    return info["fine_force_trace"][start:], info
