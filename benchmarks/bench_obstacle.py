"""Obstacle avoidance coupling (issue 13) as the no-learning baseline on the core wiping scenario.

The style-1 wiping DMP (circle of radius 5 cm about the anchor, smooth periodic fit) runs for 8 s at
500 Hz with a point obstacle in the table plane, at 4 angles on 3 radii (4.5, 5, 5.5 cm: inside, on and
outside the wiped circle), with Hoffmann et al.'s steering term (beta = 20/pi) and a Gaussian distance
window (the library's default fit, alpha_z = 5): gain 1e4 with lambda = 2 cm, gain 2e4 with lambda = 3 cm
(the env baseline's setting), and the same with the coupling low-passed over 0.1 s. Then the env baseline with a
virtual point obstacle on the wiped circle, and on ArmarWipe-v1 contexts with a cup (:func:`cup_contexts`).
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
from rdmp_gym.coupling import ObstacleAvoidance, avoiding_rollout

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
    from rdmp_gym.envs import ENV_ID
    from rdmp_gym.envs.obstacle_baseline import run_avoiding

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


def cup_contexts(count: int = 20, first_seed: int = 10_000) -> dict:
    """The baseline on ArmarWipe-v1 contexts with a cup (the first ``count`` reset seeds from ``first_seed``
    whose drawn context has one): success rate, coverage, reward, arm-cup contact steps and cup displacement
    of the imitation and of :func:`run_avoiding` (the cup from the context)."""
    import gymnasium as gym
    from rdmp_gym.envs import ENV_ID
    from rdmp_gym.envs.obstacle_baseline import run_avoiding

    env = gym.make(ENV_ID)
    rows, seed = [], first_seed
    while len(rows) < count:
        observation, _ = env.reset(seed=seed)
        if observation[10] > 0.5:
            _, imitation_reward, _, _, imitation = env.step(np.zeros(env.action_space.shape, dtype=np.float32))
            env.reset(seed=seed)
            reward, info = run_avoiding(env)
            rows.append({"seed": seed, **{f"{name}_{key}": float(source[key]) for name, source in
                                          (("imitation", imitation), ("baseline", info))
                                          for key in ("is_success", "coverage", "obstacle_touch_steps",
                                                      "obstacle_shift", "valid")},
                         "imitation_reward": float(imitation_reward), "baseline_reward": float(reward),
                         "baseline_clearance": info["obstacle_clearance"]})
        seed += 1
    summary = {}
    print(f"v1 contexts with a cup (seeds {first_seed}..{seed - 1}, {count} with a cup):")
    print(f"{'controller':<10} {'success':>7} {'coverage':>8} {'reward':>7} {'touch steps':>11} {'cup shift mm':>20}")
    for name in ("imitation", "baseline"):
        shift = 1e3 * np.array([r[f"{name}_obstacle_shift"] for r in rows])
        summary[name] = {"success_rate": float(np.mean([r[f"{name}_is_success"] for r in rows])),
                         "coverage_mean": float(np.mean([r[f"{name}_coverage"] for r in rows])),
                         "reward_mean": float(np.mean([r[f"{name}_reward"] for r in rows])),
                         "touch_steps_mean": float(np.mean([r[f"{name}_obstacle_touch_steps"] for r in rows])),
                         "touched_share": float(np.mean([r[f"{name}_obstacle_touch_steps"] > 0 for r in rows])),
                         "cup_shift_median_mm": float(np.median(shift)), "cup_shift_max_mm": float(shift.max())}
        m = summary[name]
        print(f"{name:<10} {m['success_rate']:>7.2f} {m['coverage_mean']:>8.3f} {m['reward_mean']:>7.3f} "
              f"{m['touch_steps_mean']:>11.1f} {m['cup_shift_median_mm']:>9.1f} (max {m['cup_shift_max_mm']:>6.1f})")
    return {"rows": rows, "summary": summary}


if __name__ == "__main__":
    main()
