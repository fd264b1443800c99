"""Force-profile learning (issue 13) in the MuJoCo wiping env: the force error period by period on tilted tables.

The imitation (action 0) wipes the default 12 cm patch for 10 periods on 8 tables tilted by random roll and
pitch in [-0.15, 0.15] rad (seed 0; the env's observation bounds; its sampling range is +-0.05) and on the
nominal flat table, with the admittance law only and with the learned periodic depth profile
(``force_learning=True``), each at the env's default admittance gain (0.02 m/(N s)) and at a slow one (0.004,
the default before ArmarWipe-v1). Force error: mean |F - 18 N| of the contact force averaged over 0.1 s (the
chatter of the contact above the control bandwidth removed), per period after the transient.

    python benchmarks/bench_force_learning.py [--save]
"""

from __future__ import annotations

import argparse
import json

import gymnasium as gym
import numpy as np
from output import add_save_argument, results_dir
from rdmp_gym.envs import ENV_ID
from rdmp_gym.envs.force_learning import period_force_errors

import rdmp_gym  # noqa: F401  (registers the env)

NAME = "force_learning.json"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_save_argument(parser)
    args = parser.parse_args()
    tilts = np.vstack([[0.0, 0.0], np.random.default_rng(0).uniform(-0.15, 0.15, size=(8, 2))])
    envs = {f"{name}{suffix}": gym.make(ENV_ID, n_periods=10.0, force_learning=flag, admittance_gain=gain)
            for suffix, gain in (("", 0.02), (" slow", 0.004))
            for name, flag in (("admittance", False), ("learned profile", True))}
    rows = []
    for tilt in tilts:
        for name, env in envs.items():
            env.reset(seed=0, options={"table_height": 0.0, "table_tilt": tilt.tolist(), "patch_centre": [0.0, 0.0],
                                       "patch_size": [0.12, 0.12], "sponge_start": [-0.07, 0.10, 0.08], "obstacle": 0})
            reward, info = env.step(np.zeros(env.action_space.shape, dtype=np.float32))[1::3]
            inner = env.unwrapped
            errors = period_force_errors(info["force_trace"], inner.dt, inner.dmp.transients[0].length,
                                         inner.dmp.period, inner.reward_settings.target_force)
            rows.append({"tilt": tilt.tolist(), "controller": name, "valid": bool(info["valid"]),
                         "unstable": bool(info["unstable"]), "reward": float(reward), "coverage": info["coverage"],
                         "period_errors": errors.tolist()})
    print(f"{'tilt (roll, pitch) rad':>22} {'controller':<21} {'err per period (N): 1st 2nd ... last':<52} "
          f"{'coverage':>8} {'reward':>7}")
    for row in rows:
        e = row["period_errors"]
        text = " ".join(f"{v:.2f}" for v in e)
        label = f"({row['tilt'][0]:+.3f}, {row['tilt'][1]:+.3f})"
        print(f"{label:>22} {row['controller']:<21} {text:<52} "
              f"{row['coverage']:>8.3f} {row['reward']:>7.3f}")
    summary = {}
    for name in envs:
        group = np.array([r["period_errors"] for r in rows if r["controller"] == name][1:])      # tilted only
        summary[name] = {"mean_error_per_period": group.mean(axis=0).tolist(),
                         "mean_coverage": float(np.mean([r["coverage"] for r in rows if r["controller"] == name]))}
        print(f"{name:<21} mean over the tilted tables: " + " ".join(f"{v:.2f}" for v in group.mean(axis=0))
              + f"   coverage {summary[name]['mean_coverage']:.3f}")
    results = results_dir(args.save) / NAME
    results.write_text(json.dumps({"rows": rows, "summary": summary}, indent=1))
    print(f"wrote {results}")


if __name__ == "__main__":
    main()
