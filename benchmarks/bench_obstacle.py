"""Obstacle avoidance coupling as the no-learning baseline on the core wiping scenario.

The style-1 wiping DMP (circle of radius 5 cm about the anchor, smooth periodic fit) runs for 8 s at
500 Hz with a point obstacle in the table plane, at 4 angles on 3 radii (4.5, 5, 5.5 cm: inside, on and
outside the wiped circle), with Hoffmann et al.'s steering term (beta = 20/pi) and a Gaussian distance
window (the library's default fit, alpha_z = 5): gain 1e4 with lambda = 2 cm, gain 2e4 with lambda = 3 cm
(the env baseline's setting), and the same with the coupling low-passed over 0.1 s. Then the env baseline with a
virtual point obstacle on the wiped circle, and the coupling baseline of the agents table (the approach lifted over
the cup by :class:`~rdmp_gym.dmp.coupling.LiftOver`) on ArmarWipe-v1 contexts with a cup (:func:`cup_contexts`).
Reported on the periodic part (t > 3 s): the smallest clearance
without and with the coupling, the peak acceleration, the largest change of the path where the free path
is more than 8 cm from the obstacle, and the integrated squared jerk against the free path.

    python benchmarks/bench_obstacle.py [--save]
"""

from __future__ import annotations

import argparse
import json

import numpy as np
from output import add_save_argument, results_dir

from rdmp_gym import RhythmicDMP, wiping_demonstration
from rdmp_gym.dmp.coupling import ObstacleAvoidance, avoiding_rollout

NAME = "obstacle.json"
DT = 2e-3


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_save_argument(parser)
    args = parser.parse_args()
    dmp = RhythmicDMP.fit(wiping_demonstration(1, rng=0), n_periodic=30, periodic_overlap=0.9, smoothing=0.3,
                          regularization=1e-4)      # alpha_z: the library default (5)
    t = np.arange(0.0, 8.0, DT)
    periodic = t > 3.0
    free, free_velocity = dmp.rollout(t, return_velocity=True)

    def stats(y: np.ndarray, yd: np.ndarray) -> tuple[float, float]:
        acceleration = np.gradient(yd, DT, axis=0)
        jerk = np.gradient(acceleration, DT, axis=0)
        return float(np.abs(acceleration[periodic]).max()), float(np.sum(jerk[periodic] ** 2) * DT)

    free_peak, free_jerk = stats(free, free_velocity)
    rows = []
    for gamma, scale, smoothing in ((1e4, 0.02, 0.0), (2e4, 0.03, 0.0), (2e4, 0.03, 0.1)):
        for radius in (0.045, 0.05, 0.055):
            for angle in (0.0, 0.5 * np.pi, np.pi, 1.5 * np.pi):
                obstacle = dmp.anchor + radius * np.array([np.cos(angle), np.sin(angle), 0.0])
                y, yd = avoiding_rollout(dmp, t, ObstacleAvoidance(obstacle, gamma=gamma, distance_scale=scale),
                                         smoothing=smoothing)
                peak, jerk = stats(y, yd)
                free_distance = np.linalg.norm(free - obstacle, axis=1)
                far = periodic & (free_distance > 0.08)
                rows.append({"gamma": gamma, "distance_scale": scale, "smoothing": smoothing, "radius": radius,
                             "angle": angle,
                             "free_clearance": float(free_distance[periodic].min()),
                             "clearance": float(np.linalg.norm(y - obstacle, axis=1)[periodic].min()),
                             "peak_acc": peak, "free_peak_acc": free_peak,
                             "far_change": float(np.abs(y[far] - free[far]).max()), "jerk_ratio": jerk / free_jerk})
    print(f"{'gamma':>7} {'lambda':>6} {'tau':>4} {'radius cm':>9} {'angle':>6} {'free mm':>8} {'coupled mm':>10} "
          f"{'peak acc':>8} {'far change mm':>13} {'ISJ ratio':>9}")
    for r in rows:
        print(f"{r['gamma']:>7.0e} {r['distance_scale']:>6.2f} {r['smoothing']:>4.1f} {100 * r['radius']:>9.1f} "
              f"{np.degrees(r['angle']):>6.0f} "
              f"{1e3 * r['free_clearance']:>8.2f} {1e3 * r['clearance']:>10.2f} {r['peak_acc']:>8.2f} "
              f"{1e3 * r['far_change']:>13.3f} {r['jerk_ratio']:>9.2f}")
    print(f"free path: peak acceleration {free_peak:.2f} m/s^2")
    env_rows = env_baseline()
    cups = cup_contexts()
    results = results_dir(args.save) / NAME
    results.write_text(json.dumps({"rows": rows, "env": env_rows, "cup_contexts": cups}, indent=1))
    print(f"wrote {results}")


def env_baseline() -> list[dict]:
    """The baseline in the MuJoCo env with a virtual point obstacle (no cup body): reward, coverage and clearance
    vs the imitation, default context (12 cm patch, no cup), obstacle at 4 angles on the wiped circle."""
    import gymnasium as gym
    from obstacle_baseline import run_avoiding
    from rdmp_gym.envs import ENV_ID

    env = gym.make(ENV_ID, n_periods=4.0)
    options = {"table_height": 0.0, "table_tilt": [0.0, 0.0], "patch_centre": [0.0, 0.0],
               "patch_size": [0.12, 0.12], "sponge_start": [-0.07, 0.10, 0.08], "obstacle": 0}
    env.reset(seed=0, options=options)
    inner = env.unwrapped
    free = inner.rollout_path(inner.action_map.theta0)
    _, imitation_reward, _, _, imitation = env.step(np.zeros(env.action_space.shape, dtype=np.float32))
    out = []
    for angle in (0.0, 0.5 * np.pi, np.pi, 1.5 * np.pi):
        obstacle = 0.05 * np.array([np.cos(angle), np.sin(angle)])
        env.reset(seed=0, options=options)
        reward, info = run_avoiding(env, obstacle)
        out.append({"angle": angle, "imitation_reward": imitation_reward, "imitation_coverage": imitation["coverage"],
                    "imitation_clearance": float(np.linalg.norm(free[:, :2] - obstacle, axis=1).min()),
                    "reward": reward, "coverage": info["coverage"], "clearance": info["obstacle_clearance"],
                    "valid": info["valid"]})
    print(f"{'env: angle':>10} {'imitation reward/cov/clear mm':>30} {'baseline reward/cov/clear mm':>30}")
    for r in out:
        print(f"{np.degrees(r['angle']):>10.0f} {r['imitation_reward']:>12.3f} {r['imitation_coverage']:>6.3f} "
              f"{1e3 * r['imitation_clearance']:>9.2f} {r['reward']:>12.3f} {r['coverage']:>6.3f} "
              f"{1e3 * r['clearance']:>9.2f}")
    return out


def _imitation_scores(env, seeds: np.ndarray, approach: float = 0.0) -> dict[str, np.ndarray]:
    """The imitation (action 0; ``approach``: the env's approach action dimension, last) in the contexts of
    ``seeds``, with the same fields as ``coupling_baseline_scores``."""
    from obstacle_baseline import path_jerk_ratio

    rows = []
    for seed in seeds:
        observation, _ = env.reset(seed=int(seed))
        action = np.zeros(env.action_space.shape, dtype=np.float32)
        action[-1] = approach
        reward, info = env.step(action)[1::3]
        base = env.unwrapped
        jerk = 1.0 if approach == 0.0 else path_jerk_ratio(env, base.rollout_path(base.action_to_params(action)))
        rows.append((reward, info["coverage"], info["force_in_band_fraction"], info["valid"], info["is_success"], jerk,
                     observation[10] > 0.5, info["obstacle_touch_steps"] > 0, info["obstacle_shift"],
                     info["peak_joint_accel"]))
    names = ("returns", "coverage", "force_in_band", "valid", "success", "jerk_ratio", "cup", "cup_touched",
             "cup_shift", "peak_joint_accel")
    return {"seeds": np.asarray(seeds), **{name: np.asarray(column) for name, column in
                                           zip(names, zip(*rows, strict=True), strict=True)}}


def _planar_scores(env, seeds: np.ndarray) -> dict[str, np.ndarray]:
    """The planar steering term (:func:`run_avoiding`, Hoffmann et al.) in the contexts of ``seeds``."""
    from obstacle_baseline import avoiding_path, path_jerk_ratio

    rows = []
    for seed in seeds:
        observation, _ = env.reset(seed=int(seed))
        path = avoiding_path(env)
        reward, info = env.unwrapped.run_path(path)
        rows.append((reward, info["coverage"], info["force_in_band_fraction"], info["valid"], info["is_success"],
                     path_jerk_ratio(env, path), observation[10] > 0.5, info["obstacle_touch_steps"] > 0,
                     info["obstacle_shift"], info["peak_joint_accel"]))
    names = ("returns", "coverage", "force_in_band", "valid", "success", "jerk_ratio", "cup", "cup_touched",
             "cup_shift", "peak_joint_accel")
    return {"seeds": np.asarray(seeds), **{name: np.asarray(column) for name, column in
                                           zip(names, zip(*rows, strict=True), strict=True)}}


def _summary(scores: dict[str, np.ndarray]) -> dict[str, float]:
    cup = scores["cup"].astype(bool)
    return {"success": float(np.mean(scores["success"])), "coverage": float(np.mean(scores["coverage"])),
            "returns": float(np.mean(scores["returns"])), "valid": float(np.mean(scores["valid"])),
            "cups": int(cup.sum()), "cup_touched": int(np.sum(scores["cup_touched"][cup])),
            "cup_moved_5mm": int(np.sum(scores["cup_shift"][cup] >= 0.005)),
            "cup_success": int(np.sum(scores["success"][cup])),
            "cup_coverage": float(np.mean(scores["coverage"][cup])) if cup.any() else float("nan"),
            "jerk_ratio_max": float(np.max(scores["jerk_ratio"])),
            "jerk_ratio_cup_mean": float(np.mean(scores["jerk_ratio"][cup])) if cup.any() else float("nan"),
            "joint_accel_cup_median": float(np.median(scores["peak_joint_accel"][cup])) if cup.any() else float("nan"),
            "joint_accel_cup_max": float(np.max(scores["peak_joint_accel"][cup])) if cup.any() else float("nan")}


def _first_touch(env, seeds: np.ndarray) -> list[float]:
    """Time (s) of the first arm-cup contact of the coupling baseline per seed (-1: none)."""
    from obstacle_baseline import run_lifting
    from rdmp_gym.envs.tasks.wiping import task as wipe_env

    original, times = wipe_env.simulate_wipe, []

    def tapped(*args, **kwargs):
        trace = original(*args, **kwargs)
        contact = trace.obstacle_contact
        times.append(float(np.argmax(contact)) * env.unwrapped.dt if contact.any() else -1.0)
        return trace

    wipe_env.simulate_wipe = tapped
    try:
        for seed in seeds:
            env.reset(seed=int(seed))
            run_lifting(env)
    finally:
        wipe_env.simulate_wipe = original
    return times


def cup_contexts(count: int = 40, first_seed: int = 10_000) -> dict:
    """The coupling baseline (:func:`coupling_baseline_scores`: the approach lifted over the cup) against the
    imitation (action 0) and the planar steering term, on the agents protocol's 20 test contexts
    (``final_test_seeds(20)``) and on the first ``count`` reset seeds from ``first_seed`` whose context has a cup
    (where the first contact of the baseline with the cup happens: approach or wiping)."""
    import gymnasium as gym
    from obstacle_baseline import coupling_baseline_scores
    from rdmp_gym.agents.protocol import final_test_seeds
    from rdmp_gym.envs import ENV_ID

    env = gym.make(ENV_ID)
    out = {}
    seeds_by_set = {"test": final_test_seeds(20),
                    "cups": np.array([s for s in range(first_seed, first_seed + 4 * count)
                                      if env.reset(seed=s)[0][10] > 0.5][:count])}
    for name, seeds in seeds_by_set.items():
        scores = {"imitation": _imitation_scores(env, seeds), "planar steering": _planar_scores(env, seeds),
                  "approach +1 (action)": _imitation_scores(env, seeds, approach=1.0),
                  "conservative lift": coupling_baseline_scores(env, seeds, adaptive=False),
                  "coupling baseline": coupling_baseline_scores(env, seeds)}
        out[name] = {controller: {"summary": _summary(s), "per_context": {k: np.asarray(v).tolist()
                                                                         for k, v in s.items()}}
                     for controller, s in scores.items()}
        print(f"{name}: reset seeds {seeds[0]}..{seeds[-1]} ({len(seeds)} contexts)")
        print(f"{'controller':<21} {'success':>7} {'coverage':>8} {'return':>7} {'cups':>4} {'touched':>7} "
              f"{'moved>5mm':>9} {'cov. w/ cup':>11} {'jerk max':>8} {'jerk cup mean':>13} "
              f"{'joint acc. cup med/max':>22}")
        for controller, result in out[name].items():
            m = result["summary"]
            print(f"{controller:<21} {m['success']:>7.2f} {m['coverage']:>8.3f} {m['returns']:>7.3f} {m['cups']:>4d} "
                  f"{m['cup_touched']:>7d} {m['cup_moved_5mm']:>9d} {m['cup_coverage']:>11.3f} "
                  f"{m['jerk_ratio_max']:>8.2f} {m['jerk_ratio_cup_mean']:>13.2f} "
                  f"{m['joint_accel_cup_median']:>15.1f}/{m['joint_accel_cup_max']:<6.1f}")
    touches = _first_touch(env, seeds_by_set["cups"])
    length = env.unwrapped.dmp.transients[0].length
    out["cups"]["coupling baseline"]["first_touch"] = touches
    approach = sum(0.0 <= t < length for t in touches)
    wiping = sum(t >= length for t in touches)
    print(f"coupling baseline, first cup contact: in the approach (t < {length:.2f} s) {approach}, "
          f"in the wiping {wiping}, never {touches.count(-1.0)}")
    return out


if __name__ == "__main__":
    main()
