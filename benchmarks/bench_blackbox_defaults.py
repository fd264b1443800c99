"""The rhythmic black-box wrapper's defaults on every Gymnasium MuJoCo env with a continuous action space.

Per env, ``make_blackbox(env_id)`` with no setting (Swimmer and HalfCheetah: their entries in ``ENV_DEFAULTS``; the
others: derived from the MuJoCo model, ``rdmp_gym.envs.blackbox.model_defaults``): the controller and its gains, the
default pattern's period and amplitude, and on reset seeds 0-4 the default pattern's episode (action 0: its length
in env steps, return, tracking RMS, clipped fraction) beside the raw zero action's on ``gym.make(env_id)`` (the
env's action 0 at every step: its length and return). The default pattern should last at least as long as the raw
zero action. About 1 minute on one core (Humanoid's and HumanoidStandup's 1,000 steps are the slow part).

    python benchmarks/bench_blackbox_defaults.py            # prints the table, writes runs/benchmarks/
    python benchmarks/bench_blackbox_defaults.py --save     # writes benchmarks/results/blackbox_defaults.json
    python benchmarks/bench_blackbox_defaults.py --envs Hopper-v5 Walker2d-v5 --seeds 0 1 2 3 4 5 6 7 8 9 10 11
"""

from __future__ import annotations

import argparse
import json
import os
import time
from typing import Any

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import gymnasium as gym
import numpy as np
from output import add_save_argument, results_dir
from rdmp_gym.agents.training import environment_record
from rdmp_gym.envs.blackbox import MODEL_RULES, env_defaults, make_blackbox

#: every Gymnasium MuJoCo env (v5) with a continuous action space
ENVS = ("Ant-v5", "HalfCheetah-v5", "Hopper-v5", "Humanoid-v5", "HumanoidStandup-v5", "InvertedDoublePendulum-v5",
        "InvertedPendulum-v5", "Pusher-v5", "Reacher-v5", "Swimmer-v5", "Walker2d-v5")
SEEDS = (0, 1, 2, 3, 4)


def zero_action_episode(env: gym.Env, seed: int) -> tuple[int, float]:
    """The raw env under its action 0 at every step from ``reset(seed)``: (env steps, return)."""
    env.reset(seed=seed)
    zero = np.zeros(env.action_space.shape, dtype=env.action_space.dtype)
    steps, total = 0, 0.0
    while True:
        _, reward, terminated, truncated, _ = env.step(zero)
        steps, total = steps + 1, total + float(reward)
        if terminated or truncated:
            return steps, total


def _rounded(values: Any, digits: int = 4) -> Any:
    return None if values is None else np.round(np.asarray(values, dtype=np.float64), digits).tolist()


def measure(env_id: str, seeds: tuple[int, ...]) -> dict[str, Any]:
    """The wrapper's defaults on ``env_id`` and both episodes per seed (see the module docstring)."""
    start = time.perf_counter()
    wrapped = make_blackbox(env_id)
    raw = gym.make(env_id)
    controller = wrapped.controller
    derived = wrapped.model_defaults
    episodes = []
    for seed in seeds:
        wrapped.reset(seed=seed)
        _, total, _, _, info = wrapped.step(np.zeros(wrapped.action_space.shape, np.float32))
        zero_steps, zero_return = zero_action_episode(raw, seed)
        episodes.append({"seed": seed, "pattern_steps": info["env_steps"], "pattern_return": total,
                         "tracking_rmse": info["tracking_rmse"], "clipped_fraction": info["clipped_fraction"],
                         "zero_steps": zero_steps, "zero_return": zero_return})
    wrapped.close()
    raw.close()
    mean = {key: float(np.mean([e[key] for e in episodes]))
            for key in ("pattern_steps", "pattern_return", "tracking_rmse", "clipped_fraction", "zero_steps",
                        "zero_return")}
    known = env_defaults(env_id)
    amplitude = known.get("amplitude", None if derived is None else derived.amplitude)
    return {"env": env_id, "source": "ENV_DEFAULTS" if known else "model", "joints": list(wrapped.joint_names),
            "controller": getattr(controller, "name", "callable"),
            "p_gains": _rounded(getattr(controller, "p_gains", None)),
            "d_gains": _rounded(getattr(controller, "d_gains", None)),
            "period": float(wrapped.dmp.period), "amplitude": _rounded(np.broadcast_to(amplitude, (
                wrapped.n_joints,))),
            "passive_joints": list(derived.passive) if derived is not None else [],
            "episode_limit": wrapped.n_steps, "episodes": episodes, "mean": mean,
            "pattern_lasts_as_long": all(e["pattern_steps"] >= e["zero_steps"] for e in episodes),
            "mean_lasts_as_long": mean["pattern_steps"] >= mean["zero_steps"],
            "seconds": round(time.perf_counter() - start, 1)}


def table(rows: list[dict[str, Any]]) -> str:
    """A markdown table of the rows' means."""
    lines = ["| env | controller | Kp (min-max) | Kd (min-max) | period (s) | pattern: steps, return | "
             "zero action: steps, return | tracking RMS | clipped |",
             "|---|---|---|---|---|---|---|---|---|"]
    for row in rows:
        mean = row["mean"]

        def span(values: list[float] | None) -> str:
            return "-" if values is None else f"{min(values):.3g}-{max(values):.3g}"

        lines.append(f"| {row['env']} | {row['controller']} ({row['source']}) | {span(row['p_gains'])} | "
                     f"{span(row['d_gains'])} | {row['period']:.2f} | {mean['pattern_steps']:.0f}, "
                     f"{mean['pattern_return']:.1f} | {mean['zero_steps']:.0f}, {mean['zero_return']:.1f} | "
                     f"{mean['tracking_rmse']:.3f} | {mean['clipped_fraction']:.3f} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--envs", nargs="+", default=list(ENVS))
    parser.add_argument("--seeds", nargs="+", type=int, default=list(SEEDS))
    add_save_argument(parser)
    args = parser.parse_args(argv)
    rows = []
    for env_id in args.envs:
        rows.append(measure(env_id, tuple(args.seeds)))
        row = rows[-1]
        print(f"{env_id}: pattern {[e['pattern_steps'] for e in row['episodes']]} steps, zero action "
              f"{[e['zero_steps'] for e in row['episodes']]} ({row['seconds']} s)", flush=True)
    print(table(rows))
    document = {"command": "python benchmarks/bench_blackbox_defaults.py" + (" --save" if args.save else ""),
                "seeds": args.seeds, "model_rules": MODEL_RULES, "rows": rows,
                "all_last_as_long_per_seed": all(row["pattern_lasts_as_long"] for row in rows),
                "all_last_as_long_on_average": all(row["mean_lasts_as_long"] for row in rows),
                "environment": environment_record()}
    target = results_dir(args.save) / "blackbox_defaults.json"
    target.write_text(json.dumps(document, indent=1) + "\n")
    print(f"wrote {target}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
