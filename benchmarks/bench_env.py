"""Benchmark of rdmp_gym/ArmarWipe-v1: episode cost vs bare MuJoCo stepping, the imitation's quality, the pad
contact at 500 Hz, and the cheap strategies that tried to game the reward against the imitation.

Measures, in one run on one model:

- the CPU time of one default episode (``step(0)``: DMP rollout, path IK, simulation with force adaptation,
  contact/wear/collision bookkeeping, reward) against bare stepping of the same physics (same model, same
  start state, the same servo targets at the control rate, nothing but ``mujoco.mj_step(model, data,
  frame_skip)``), interleaved, median of ``--repeats`` (target: env <= 1.5 x bare);
- the sponge–table force at every 2 ms physics step on a level table (mean, SD, drops to 0 N), against
  the stored ArmarWipe-v0 trace (``results/env_force_v0.npz``), plotted to ``results/env_force.png``;
- action 0 over ``--contexts`` seeded contexts (obstacle on, as in the benchmark task): reward, coverage,
  force, success rate, how often the cup is in the approach and how often the imitation disturbs it;
- the gaming probes 1-8: each cheap strategy in the same context as the imitation.

Prints tables and writes ``benchmarks/results/env.json``.
Run: ``MUJOCO_GL=egl nice -n 5 python benchmarks/bench_env.py`` (seeds 0..contexts-1; random actions from
``numpy.random.default_rng(seed)``).
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
import probes
import rdmp_gym.envs  # noqa: F401  (registers the env)
from output import add_save_argument, results_dir
from rdmp_gym.envs import ENV_ID
from rdmp_gym.envs.controller import JointTargetPlan
from rdmp_gym.envs.tasks.wiping.scene import TablePose, control_frame

RESULTS = Path(__file__).resolve().parent / "results"
NOMINAL = {"table_height": 0.0, "table_tilt": [0.0, 0.0], "patch_centre": [0.0, 0.0], "patch_size": [0.12, 0.12],
           "sponge_start": [-0.07, 0.22, 0.12], "obstacle": 0}
# the "before" numbers (ArmarWipe-v0, as reported against it; item 4 re-measured, results/env_force_v0.npz)
BEFORE = {
    "1_offtable_patch": "patch (-0.15, 0) 0.12 m: 84 of 144 cells in the air, coverage 1.0, reward 1.148",
    "2_self_penetration": ("patch (-0.15, 0.20): forearm 56 mm inside the torso, sponge 37 mm inside the "
                           "platform; valid"),
    "3_hold_still": "0.10 m patch: coverage 0.80, reward 0.996 (imitation ~1.0)",
    "3_press_lift": "0.22 m patch, 3x3 grid: coverage 0.93, reward 0.874 vs imitation 0.651 / 0.796",
    "4_chatter": "level table: SD 5.0 N around 18.3 N, 20 single-step drops to 0 N per second",
    "5_tilt": "0.15 rad tilt: coverage 0.36-0.58 for action 0; lowest+tilted+far corner: coverage 0, valid",
    "6_touchdown": "table 6 cm higher: 74 N impact, no cost",
    "7_smoothness": "random actions beat the imitation on 11 of 20 contexts; alternating +-1: 0.964 vs 0.974",
    "8_approach": "no obstacle; nothing but reaching the table depends on the transient",
}


def zero(env) -> np.ndarray:
    return np.zeros(env.action_space.shape, dtype=np.float32)


def episode(env, options, action=None, seed=0) -> tuple[float, dict]:
    env.reset(seed=seed, options=options)
    _, reward, _, _, info = env.step(zero(env) if action is None else action)
    return reward, info


def path_episode(env, options, make_path, seed=0) -> tuple[float, dict]:
    env.reset(seed=seed, options=options)
    return env.unwrapped.run_path(make_path(env.unwrapped))


def summary(reward: float, info: dict) -> dict:
    keys = ("coverage", "force_mean", "force_sd", "force_in_band_fraction", "impact_force", "jerk_ratio",
            "peak_joint_accel", "self_collision_fraction", "penetration", "obstacle_touch_steps", "obstacle_shift",
            "valid", "invalid_reason", "is_success")
    out = {"reward": float(reward)}
    for key in keys:
        value = info[key]
        out[key] = value if isinstance(value, (bool, str)) else float(value)
    return out


def timing(env, repeats: int) -> dict:
    """Interleaved CPU time of the env episode and of bare stepping (same physics)."""
    u = env.unwrapped
    env.reset(seed=0, options=NOMINAL)
    env.step(zero(env))                       # warm up
    env_cpu, bare_cpu, env_wall, bare_wall = [], [], [], []
    for _ in range(repeats):
        env.reset(seed=0, options=NOMINAL)
        wall, cpu = time.perf_counter(), time.process_time()
        env.step(zero(env))
        env_cpu.append(time.process_time() - cpu)
        env_wall.append(time.perf_counter() - wall)
        env.reset(seed=0, options=NOMINAL)
        path = u.rollout_path(u.action_map.theta0)
        solution = u.task.solve_path(path, u.context)
        plan = JointTargetPlan(solution, u.dt, u.scene.servo_lead(), u.scene.joint_lower, u.scene.joint_upper,
                               control_frame(u.task.parts, TablePose.of(u.context))[1][:, 2])
        preload = u.task.adaptation_settings.target_force / u.task.adaptation_settings.stiffness
        ctrl = plan.q - preload * plan.normal_dq
        m, d = u.scene.model, u.scene.data
        u.scene.set_arm_state(solution.q[0])
        index = slice(int(u.scene.actuator_ids[0]), int(u.scene.actuator_ids[0]) + 10)
        step, skip = mujoco.mj_step, u.frame_skip
        wall, cpu = time.perf_counter(), time.process_time()
        for row in ctrl:
            d.ctrl[index] = row
            step(m, d, skip)
        bare_cpu.append(time.process_time() - cpu)
        bare_wall.append(time.perf_counter() - wall)
    physics = u.n_steps * u.frame_skip
    e, b = float(np.median(env_cpu)), float(np.median(bare_cpu))
    return {"env_episode_cpu_s": e, "bare_stepping_cpu_s": b, "env_over_bare_cpu": e / b,
            "env_episode_wall_s": float(np.median(env_wall)), "bare_stepping_wall_s": float(np.median(bare_wall)),
            "env_over_bare_wall": float(np.median(env_wall) / np.median(bare_wall)),
            "env_physics_steps_per_cpu_s": physics / e, "bare_physics_steps_per_cpu_s": physics / b,
            "target_env_over_bare": 1.5, "repeats": repeats}


def force_at_500hz(env, plot: Path | None) -> dict:
    """Level-table pad force at every physics step (v1) against the stored v0 trace; optional plot."""
    dt = env.unwrapped.scene.model.opt.timestep
    after, _ = probes.wiping_force_at_500hz(env, NOMINAL)                       # from 0.5 s into the wiping phase
    v0 = np.load(RESULTS / "env_force_v0.npz")
    before_all = v0["force"]
    before = before_all[round((float(v0["transient"]) + 0.5) / float(v0["timestep"])):]

    def stats(force: np.ndarray) -> dict:
        return {"mean_N": float(force.mean()), "sd_N": float(force.std()), "min_N": float(force.min()),
                "zero_drops_per_s": float(np.count_nonzero(force < 0.5) / (len(force) * dt)),
                "seconds": float(len(force) * dt)}

    result = {"v0": stats(before), "v1": stats(after)}
    if plot is not None:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, axes = plt.subplots(2, 1, figsize=(9, 5), sharex=True, sharey=True)
        window = round(1.0 / dt)
        for ax, force, name in ((axes[0], before, "v0 (rigid pad on a slide, stiff contact)"),
                                (axes[1], after, "v1 (soft foam contact, tilting pad mount)")):
            s = result["v0" if ax is axes[0] else "v1"]
            ax.plot(np.arange(window) * dt, force[:window], lw=0.8)
            ax.axhline(18.0, color="k", lw=0.5, ls="--")
            ax.set_title(f"ArmarWipe-{name}: SD {s['sd_N']:.2f} N, {s['zero_drops_per_s']:.1f} drops to 0 N per s",
                         fontsize=9)
            ax.set_ylabel("normal force (N)")
        axes[1].set_xlabel("time (s), 1 s of wiping sampled at 500 Hz (every physics step)")
        fig.tight_layout()
        fig.savefig(plot, dpi=110)
        plt.close(fig)
    return result


def imitation_quality(env, contexts: int) -> dict:
    rows = []
    for seed in range(contexts):
        obs, _ = env.reset(seed=seed)
        reward, info = episode(env, None, seed=seed)
        row = summary(reward, info)
        row.update({"seed": seed, "obstacle": bool(obs[10] > 0.5), "patch_size": obs[5:7].tolist()})
        rows.append(row)

    def stats(key, table):
        values = np.array([r[key] for r in table], dtype=float)
        return {"mean": float(values.mean()), "min": float(values.min()), "max": float(values.max())} if len(
            values) else {}

    cup = [r for r in rows if r["obstacle"]]
    free = [r for r in rows if not r["obstacle"]]
    return {
        "contexts": contexts,
        "all": {k: stats(k, rows) for k in ("reward", "coverage", "force_mean", "force_sd", "force_in_band_fraction",
                                            "impact_force", "peak_joint_accel")},
        "without_cup": {k: stats(k, free) for k in ("reward", "coverage")},
        "with_cup": {k: stats(k, cup) for k in ("reward", "coverage", "obstacle_shift")},
        "cup_share": len(cup) / contexts,
        "cup_disturbed_share": float(np.mean([r["obstacle_touch_steps"] > 0 or r["obstacle_shift"] > 0.005
                                              for r in cup])) if cup else None,
        "success_rate": float(np.mean([r["is_success"] for r in rows])),
        "valid_fraction": float(np.mean([r["valid"] for r in rows])),
        "per_context": rows,
    }


def issue_items(env, contexts: int) -> dict:
    """The gaming probes 1-8, after: each cheap strategy next to the imitation in the same context."""
    u = env.unwrapped
    items: dict[str, dict] = {}
    try:
        env.reset(options={**NOMINAL, "patch_centre": [-0.15, 0.0]})
        items["1_offtable_patch"] = {"result": "no ValueError (bug)"}
    except ValueError as error:
        items["1_offtable_patch"] = {"result": f"ValueError: {error}"}
    env.reset(seed=0, options=NOMINAL)
    start = int(np.argmax(u.task.periodic))
    into = probes._blend(probes._imitation(u), np.tile([-0.30, 0.28, 0.15], (u.n_steps, 1)), start, 250)
    imitation = summary(*episode(env, NOMINAL))
    edge = {**NOMINAL, "patch_centre": [-0.09, 0.2], "patch_size": [0.10, 0.10]}
    items["2_self_penetration"] = {"imitation": imitation,
                                   "reach_into_torso": summary(*path_episode(env, NOMINAL, lambda _: into)),
                                   "edge_patch_-0.09_0.20": summary(*episode(env, edge))}
    small = {**NOMINAL, "patch_size": [0.10, 0.10]}
    items["3_hold_still"] = {"imitation": summary(*episode(env, small)),
                             "hold_still": summary(*path_episode(env, small, probes.hold_still))}
    large = {**NOMINAL, "patch_size": [0.22, 0.22]}
    items["3_press_lift"] = {"imitation": summary(*episode(env, large)),
                             "press_lift_3x3": summary(*path_episode(env, large, probes.press_lift_grid))}
    tilts = {}
    level = summary(*episode(env, NOMINAL))
    for tilt in ((0.15, 0.0), (-0.15, 0.0), (0.0, 0.15), (0.0, -0.15), (0.15, 0.15), (-0.15, -0.15), (0.15, -0.15),
                 (-0.15, 0.15)):
        tilts[str(tilt)] = summary(*episode(env, {**NOMINAL, "table_tilt": list(tilt)}))
    worst = summary(*episode(env, {**NOMINAL, "table_height": -0.06, "table_tilt": [0.15, 0.15],
                                   "patch_centre": [0.15, -0.20], "patch_size": [0.30, 0.30]}))
    items["5_tilt"] = {"level": level, "tilted": tilts, "lowest_tilted_far_corner_largest": worst}
    higher = {**NOMINAL, "table_height": 0.06}

    def slam(env_u):
        path = env_u.rollout_path(env_u.action_map.theta0)
        z = path[:, 2]
        k = int(np.flatnonzero(z < 0.05)[0])
        steps = np.arange(len(z))
        path[:, 2] = np.where(steps >= k, np.interp(steps, [k, k + 12], [z[k], -0.03]), z)
        return path

    items["6_touchdown"] = {"imitation_table_6cm_higher": summary(*episode(env, higher)),
                            "imitation_level": level, "slam_3cm_into_table": summary(*path_episode(env, NOMINAL, slam))}
    beaten, pairs = 0, []
    slices = env.unwrapped.action_map.slices
    for seed in range(contexts):
        r0, _ = episode(env, {"obstacle": 0}, seed=seed)
        action = np.random.default_rng(seed).uniform(-1, 1, env.action_space.shape).astype(np.float32)
        r, info = episode(env, {"obstacle": 0}, action, seed=seed)
        twin = action.copy()                 # the same action without its weight entries: same coverage, smooth
        twin[slices["periodic"]] = 0.0
        twin[slices["transient:0"]] = 0.0
        r_twin, info_twin = episode(env, {"obstacle": 0}, twin, seed=seed)
        beaten += r > r0
        pairs.append({"seed": seed, "imitation": r0, "random": r, "jerk_ratio": info["jerk_ratio"],
                      "peak_joint_accel": info["peak_joint_accel"], "coverage": info["coverage"],
                      "smooth_twin": r_twin, "smooth_twin_jerk_ratio": info_twin["jerk_ratio"],
                      "smooth_twin_coverage": info_twin["coverage"]})
    alternating = np.where(np.arange(env.action_space.shape[0]) % 2 == 0, 1.0, -1.0).astype(np.float32)
    items["7_smoothness"] = {"random_beats_imitation": f"{beaten} of {contexts}", "random": pairs,
                             "imitation_seed0": summary(*episode(env, {"obstacle": 0})),
                             "alternating_pm1_seed0": summary(*episode(env, {"obstacle": 0}, alternating))}
    cup = {**NOMINAL, "obstacle": 1}
    lift = zero(env)
    lift[-1] = 1.0                           # the approach dimension: +6 cm over the corridor
    sampled = []
    for seed in range(contexts):
        env.reset(seed=seed)
        if not env.unwrapped.context.obstacle:
            continue
        r0, i0 = episode(env, None, seed=seed)
        r1, i1 = episode(env, None, lift, seed=seed)
        sampled.append({"seed": seed, "imitation": r0, "imitation_touch_steps": i0["obstacle_touch_steps"],
                        "lifted": r1, "lifted_touch_steps": i1["obstacle_touch_steps"],
                        "lifted_obstacle_shift": i1["obstacle_shift"], "lifted_jerk_ratio": i1["jerk_ratio"]})
    items["8_approach"] = {"imitation_without_cup": summary(*episode(env, NOMINAL)),
                           "imitation_with_cup": summary(*episode(env, cup)),
                           "approach_action_with_cup": summary(*episode(env, cup, lift)),
                           "approach_action_lowered_with_cup": summary(*episode(env, cup, -lift)),
                           "sampled_cup_contexts": sampled}
    return items


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--contexts", type=int, default=20, help="seeded contexts for the statistics")
    parser.add_argument("--repeats", type=int, default=7, help="timing repetitions (median reported)")
    parser.add_argument("--n-periods", type=float, default=4.0)
    parser.add_argument("--out", type=Path, default=None, help="output JSON (default: env.json, see --save)")
    parser.add_argument("--plot", type=Path, default=None, help="force plot (default: env_force.png, see --save)")
    add_save_argument(parser)
    args = parser.parse_args()
    args.out = args.out or results_dir(args.save) / "env.json"
    args.plot = args.plot or results_dir(args.save) / "env_force.png"

    env = gym.make(ENV_ID, n_periods=args.n_periods)
    u = env.unwrapped
    result = {
        "machine": {"python": platform.python_version(), "mujoco": mujoco.__version__, "cpus": os.cpu_count(),
                    "processor": platform.processor() or platform.machine()},
        "env": ENV_ID,
        "episode": {"control_steps": u.n_steps, "physics_steps": u.n_steps * u.frame_skip, "frame_skip": u.frame_skip,
                    "simulated_seconds": u.n_steps * u.dt, "action_dim": int(env.action_space.shape[0])},
        "timing": timing(env, args.repeats),
        "force_500hz": force_at_500hz(env, args.plot),
        "imitation_quality": imitation_quality(env, args.contexts),
        "issue_8_before": BEFORE,
        "issue_8_after": issue_items(env, args.contexts),
    }
    env.close()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2))

    t = result["timing"]
    print(f"{ENV_ID}: {u.n_steps} control steps x {u.frame_skip} = {u.n_steps * u.frame_skip} physics steps "
          f"({u.n_steps * u.dt:.2f} s simulated), action dim {result['episode']['action_dim']}")
    print(f"env episode {t['env_episode_cpu_s']:.4f} s CPU, bare mj_step {t['bare_stepping_cpu_s']:.4f} s CPU: "
          f"env / bare {t['env_over_bare_cpu']:.2f} (wall {t['env_over_bare_wall']:.2f}; target <= 1.5)")
    f = result["force_500hz"]
    print(f"\npad force at 500 Hz, level table, wiping: {'':6s}{'mean N':>8s}{'SD N':>8s}{'min N':>8s}{'drops/s':>9s}")
    for name in ("v0", "v1"):
        s = f[name]
        print(f"  {name:42s}{s['mean_N']:8.2f}{s['sd_N']:8.2f}{s['min_N']:8.2f}{s['zero_drops_per_s']:9.1f}")
    q = result["imitation_quality"]
    print(f"\naction 0 over {args.contexts} seeded contexts (cup in {q['cup_share']:.0%} of them):")
    for key, s in q["all"].items():
        print(f"  {key:26s}{s['mean']:9.3f}{s['min']:9.3f}{s['max']:9.3f}")
    print(f"  reward without / with cup: {q['without_cup']['reward']['mean']:.3f} / "
          f"{q['with_cup']['reward'].get('mean', float('nan')):.3f}; cup disturbed in "
          f"{q['cup_disturbed_share']} of cup contexts; success rate {q['success_rate']:.2f}; "
          f"valid {q['valid_fraction']:.2f}")
    print("\ngaming probes (reward, coverage):")
    for item, entries in result["issue_8_after"].items():
        print(f"  {item}  [before: {BEFORE[item]}]")
        for name, value in entries.items():
            if isinstance(value, dict) and "reward" in value:
                print(f"    {name:34s} reward {value['reward']:7.3f}  coverage {value['coverage']:.3f}  "
                      f"valid {value['valid']}  {value['invalid_reason']}")
            elif isinstance(value, dict):
                for sub, v in value.items():
                    print(f"    {name} {sub:24s} reward {v['reward']:7.3f}  coverage {v['coverage']:.3f}  "
                          f"valid {v['valid']} {v['invalid_reason']}")
            elif not isinstance(value, list):
                print(f"    {name}: {value}")
    pairs = result["issue_8_after"]["7_smoothness"]["random"]
    if pairs:
        print(f"  random actions: jerk ratio {min(p['jerk_ratio'] for p in pairs):.1f}-"
              f"{max(p['jerk_ratio'] for p in pairs):.1f}, below the imitation by >= "
              f"{min(p['imitation'] - p['random'] for p in pairs):.3f}, below their smooth twin (same coverage "
              f"within {max(abs(p['coverage'] - p['smooth_twin_coverage']) for p in pairs):.3f}) by >= "
              f"{min(p['smooth_twin'] - p['random'] for p in pairs):.3f}")
    sampled = result["issue_8_after"]["8_approach"]["sampled_cup_contexts"]
    if sampled:
        cleared = sum(s["lifted_touch_steps"] == 0 and s["lifted_obstacle_shift"] < 0.005 for s in sampled)
        print(f"  approach +1 in {len(sampled)} sampled cup contexts: cup untouched in {cleared}, reward "
              f"{np.mean([s['imitation'] for s in sampled]):.3f} -> {np.mean([s['lifted'] for s in sampled]):.3f}")
    print(f"wrote {args.out} and {args.plot}")


if __name__ == "__main__":
    main()
