"""Benchmark of rdmp_gym/ArmarWipe-v0: episode cost vs bare MuJoCo stepping, and the imitation's quality.

Measures, in one run on one model:

- the wall time of one default episode (``reset`` + ``step(0)``: DMP rollout, path IK, simulation
  with force adaptation and contact/coverage bookkeeping, reward) and its parts;
- bare stepping: the same episode's physics (same model, same start state, the same servo targets
  at the control rate) with nothing but ``mujoco.mj_step(model, data, frame_skip)`` per control step;
- physics steps per second of both, and their ratio (target: env <= 1.5 x the bare stepping cost),
  as medians and minima of wall time and as the median of process CPU time (on a shared machine the
  CPU-time ratio is the robust one);
- coverage and force statistics of action 0 over 20 seeded contexts.

Prints a table and writes ``benchmarks/results/env.json``. Run: ``MUJOCO_GL=egl python benchmarks/bench_env.py``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import gymnasium as gym
import mujoco
import numpy as np
from output import add_save_argument, results_dir
from rdmp_gym.envs import ENV_ID
from rdmp_gym.envs.controller import JointTargetPlan

import rdmp_gym  # noqa: F401  (registers the env)


def bare_stepping(u, q0: np.ndarray, ctrl: np.ndarray) -> tuple[float, float]:
    """(wall, CPU) seconds to replay ``ctrl [T, 10]`` from rest at ``q0`` with only ``mj_step(m, d, frame_skip)``."""
    m, d = u.scene.model, u.scene.data
    u.scene.set_arm_state(q0)
    index = slice(int(u.scene.actuator_ids[0]), int(u.scene.actuator_ids[0]) + 10)
    step, skip = mujoco.mj_step, u.frame_skip
    wall, cpu = time.perf_counter(), time.process_time()
    for row in ctrl:
        d.ctrl[index] = row
        step(m, d, skip)
    return time.perf_counter() - wall, time.process_time() - cpu


def episode_parts(u, options: dict) -> dict[str, float]:
    """Wall time of the parts of one episode (same work as ``step``, timed piece by piece)."""
    theta = u.action_map.theta0
    t0 = time.perf_counter()
    path = u.rollout_path(theta)
    t1 = time.perf_counter()
    solution = u._solve(path)
    t2 = time.perf_counter()
    u.run_path(path)                           # IK again + simulation + reward
    t3 = time.perf_counter()
    return {"dmp_rollout_s": t1 - t0, "path_ik_s": t2 - t1, "simulate_and_reward_s": (t3 - t2) - (t2 - t1),
            "_solution": solution}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--contexts", type=int, default=20, help="seeded contexts for the quality statistics")
    parser.add_argument("--repeats", type=int, default=11, help="timing repetitions (median and minimum reported)")
    parser.add_argument("--n-periods", type=float, default=4.0)
    parser.add_argument("--out", type=Path, default=None, help="output JSON (default: env.json, see --save)")
    add_save_argument(parser)
    args = parser.parse_args()
    args.out = args.out or results_dir(args.save) / "env.json"

    env = gym.make(ENV_ID, n_periods=args.n_periods)
    u = env.unwrapped
    zero = np.zeros(env.action_space.shape, dtype=np.float32)
    physics_steps = u.n_steps * u.frame_skip
    options = {"table_height": 0.0, "table_tilt": [0.0, 0.0], "patch_centre": [0.0, 0.0],
               "patch_size": [0.12, 0.12], "sponge_start": [-0.07, 0.10, 0.08]}

    # warm up (fit cache, first-call overheads)
    env.reset(seed=0, options=options)
    env.step(zero)

    env_times, bare_times, env_cpu, bare_cpu, parts = [], [], [], [], []
    for _ in range(args.repeats):
        env.reset(seed=0, options=options)
        start, cpu = time.perf_counter(), time.process_time()
        env.step(zero)
        env_times.append(time.perf_counter() - start)
        env_cpu.append(time.process_time() - cpu)
        env.reset(seed=0, options=options)
        part = episode_parts(u, options)
        solution = part.pop("_solution")
        parts.append(part)
        plan = JointTargetPlan(solution, u.dt, u.scene.servo_lead(), u.scene.joint_lower, u.scene.joint_upper)
        preload = u.adaptation_settings.target_force / u.adaptation_settings.stiffness
        ctrl = plan.q - preload * plan.normal_dq
        wall, cpu = bare_stepping(u, solution.q[0], ctrl)
        bare_times.append(wall)
        bare_cpu.append(cpu)
    env_s, bare_s = float(np.median(env_times)), float(np.median(bare_times))
    env_cpu_s, bare_cpu_s = float(np.median(env_cpu)), float(np.median(bare_cpu))
    part_s = {key: float(np.median([p[key] for p in parts])) for key in parts[0]}

    rows = []
    for seed in range(args.contexts):
        env.reset(seed=seed)
        _, reward, _, _, info = env.step(zero)
        rows.append({"seed": seed, "reward": reward, "coverage": info["coverage"], "force_mean": info["force_mean"],
                     "force_in_band_fraction": info["force_in_band_fraction"],
                     "force_error_mean": info["force_error_mean"], "contact_fraction": info["contact_fraction"],
                     "max_force": info["max_force"], "valid": info["valid"], "unstable": info["unstable"],
                     "patch_size": env.unwrapped.context.patch_size.tolist()})
    rows_default = []
    for seed in range(args.contexts):
        env.reset(seed=seed, options={"patch_size": [0.12, 0.12]})
        _, reward, _, _, info = env.step(zero)
        rows_default.append({"coverage": info["coverage"], "force_in_band_fraction": info["force_in_band_fraction"]})
    env.close()

    def stats(key: str, table: list[dict]) -> dict[str, float]:
        values = np.array([r[key] for r in table], dtype=float)
        return {"mean": float(values.mean()), "min": float(values.min()), "max": float(values.max())}

    result = {
        "machine": {"python": platform.python_version(), "mujoco": mujoco.__version__, "cpus": os.cpu_count(),
                    "processor": platform.processor() or platform.machine()},
        "episode": {"control_steps": u.n_steps, "physics_steps": physics_steps, "frame_skip": u.frame_skip,
                    "simulated_seconds": physics_steps * u.scene.model.opt.timestep,
                    "action_dim": int(env.action_space.shape[0])},
        "timing": {"env_episode_s": env_s, "bare_stepping_s": bare_s,
                   "env_physics_steps_per_s": physics_steps / env_s,
                   "bare_physics_steps_per_s": physics_steps / bare_s,
                   "env_over_bare": env_s / bare_s, "target_env_over_bare": 1.5,
                   "env_episode_min_s": float(np.min(env_times)), "bare_stepping_min_s": float(np.min(bare_times)),
                   "env_over_bare_of_minima": float(np.min(env_times) / np.min(bare_times)),
                   "env_episode_cpu_s": env_cpu_s, "bare_stepping_cpu_s": bare_cpu_s,
                   "env_over_bare_cpu": env_cpu_s / bare_cpu_s, **part_s,
                   "repeats": args.repeats},
        "imitation_quality": {
            "contexts": args.contexts,
            "sampled_contexts": {k: stats(k, rows) for k in ("reward", "coverage", "force_mean",
                                                            "force_in_band_fraction", "force_error_mean",
                                                            "contact_fraction", "max_force")},
            "patch_0.12m": {k: stats(k, rows_default) for k in ("coverage", "force_in_band_fraction")},
            "valid_fraction": float(np.mean([r["valid"] for r in rows])),
            "unstable_fraction": float(np.mean([r["unstable"] for r in rows])),
            "per_context": rows,
        },
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2))

    t = result["timing"]
    print(f"ArmarWipe-v0, {u.n_steps} control steps x {u.frame_skip} = {physics_steps} physics steps "
          f"({result['episode']['simulated_seconds']:.2f} s simulated), action dim {result['episode']['action_dim']}")
    print(f"{'':34s}{'wall s':>10s}{'physics steps/s':>18s}")
    print(f"{'env episode (reset excluded)':34s}{env_s:10.4f}{t['env_physics_steps_per_s']:18,.0f}")
    print(f"{'bare mj_step, same physics':34s}{bare_s:10.4f}{t['bare_physics_steps_per_s']:18,.0f}")
    print(f"{'env / bare (median wall)':34s}{t['env_over_bare']:10.2f}   (target <= 1.5)")
    print(f"{'env / bare (minimum wall)':34s}{t['env_over_bare_of_minima']:10.2f}")
    print(f"{'env / bare (median CPU time)':34s}{t['env_over_bare_cpu']:10.2f}   "
          f"({env_cpu_s:.4f} s / {bare_cpu_s:.4f} s; insensitive to other jobs on the machine)")
    for key in ("dmp_rollout_s", "path_ik_s", "simulate_and_reward_s"):
        print(f"  {key:32s}{t[key]:10.4f}")
    q = result["imitation_quality"]
    print(f"\naction 0 over {args.contexts} seeded contexts (patch sizes 0.10-0.22 m):")
    print(f"{'':26s}{'mean':>9s}{'min':>9s}{'max':>9s}")
    for key, s in q["sampled_contexts"].items():
        print(f"{key:26s}{s['mean']:9.3f}{s['min']:9.3f}{s['max']:9.3f}")
    print("same contexts with a 0.12 m patch:")
    for key, s in q["patch_0.12m"].items():
        print(f"{key:26s}{s['mean']:9.3f}{s['min']:9.3f}{s['max']:9.3f}")
    print(f"valid {q['valid_fraction']:.2f}, unstable {q['unstable_fraction']:.2f}; wrote {args.out}")


if __name__ == "__main__":
    main()
