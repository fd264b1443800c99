"""Force-profile learning in the MuJoCo wiping env: the force error period by period.

The imitation (action 0) wipes the default 12 cm patch for 10 periods on the nominal flat table and on 8 tables
tilted by random roll and pitch in [-0.15, 0.15] rad (seed 0; the env's observation bounds; its sampling range
is +-0.05), no cup, with the admittance law only and with the learned periodic depth profile
(``force_learning=True``), each at the env's default admittance gain (0.02 m/(N s)) and at a slow one (0.004,
the default before ArmarWipe-v1). Force error: mean |F - 18 N| of the sponge-table contact force at every
physics step (500 Hz, unsmoothed), per period after the transient. Also the first harmonic (amplitude, N) of the
last period's error of the contact force and of the wrist force (what the controller measures), and the first
harmonic of their difference (the hand's and sponge's dynamics between the sensor and the contact).

Then the same on a curved table (``curved_table_scene``: the top an ellipsoid of half height 6 cm, the wiped
patch 1-17 mm below the plane the controller plans on; not tilted), and ``wavy_contact`` (a curved surface
without MuJoCo, 3 mm and 1 mm harmonics along
the period, pressed through a 30 ms servo lag, force measured exactly): 15 periods at both gains.

    python benchmarks/bench_force_learning.py [--save]
"""

from __future__ import annotations

import argparse
import json

import gymnasium as gym
import numpy as np
import rdmp_gym.envs  # noqa: F401  (registers the env)
from output import add_save_argument, results_dir
from rdmp_gym.envs import ENV_ID
from rdmp_gym.envs.controller import ForceAdaptation, ForceAdaptationSettings
from rdmp_gym.envs.tasks.wiping import env as wipe_env_module
from rdmp_gym.envs.tasks.wiping.force_learning import (
    ForceProfileLearning,
    curved_table_scene,
    period_force_errors,
    wavy_contact,
)

NAME = "force_learning.json"
DT, PERIOD = 0.01, 1.5           # the synthetic contact's control period and period (s)
OPTIONS = {"table_height": 0.0, "patch_centre": [0.0, 0.0], "patch_size": [0.12, 0.12],
           "sponge_start": [-0.07, 0.10, 0.08], "obstacle": 0}


def first_harmonic(signal: np.ndarray) -> float:
    """Amplitude of the first harmonic of one period ``[n]`` of a signal."""
    return float(2.0 * np.abs(np.fft.rfft(signal)[1]) / signal.size)


class _TraceTap:
    """Keeps the last :class:`WipeTrace` the env simulated (for the wrist force, which ``info`` does not carry)."""

    def __init__(self) -> None:
        self.original = wipe_env_module.simulate_wipe
        self.trace = None

    def __call__(self, *args, **kwargs):
        self.trace = self.original(*args, **kwargs)
        return self.trace


def episode(env, tilt: np.ndarray, tap: _TraceTap) -> dict:
    env.reset(seed=0, options={**OPTIONS, "table_tilt": tilt.tolist()})
    inner = env.unwrapped
    inner.task.fine_force = True
    reward, info = env.step(np.zeros(env.action_space.shape, dtype=np.float32))[1::3]
    start, period, target = inner.dmp.transients[0].length, inner.dmp.period, inner.task.reward_settings.target_force
    fine_dt = inner.dt / inner.frame_skip
    errors = period_force_errors(info["fine_force_trace"], fine_dt, start, period, target, smoothing=0.0)
    steps = round(period / inner.dt)
    last = slice(tap.trace.steps - steps, tap.trace.steps)
    contact, wrist = tap.trace.contact_force[last] - target, tap.trace.wrist_force[last] - target
    return {"tilt": tilt.tolist(), "valid": bool(info["valid"]), "unstable": bool(info["unstable"]),
            "reward": float(reward), "coverage": info["coverage"], "period_errors": errors.tolist(),
            "contact_h1": first_harmonic(contact), "wrist_h1": first_harmonic(wrist),
            "difference_h1": first_harmonic(contact - wrist)}


def synthetic(periods: int = 15) -> dict:
    """Per-period error on the synthetic wavy contact (exact force measurement) at both gains."""
    out = {}
    for gain in (0.02, 0.004):
        settings = ForceAdaptationSettings(target_force=18.0, gain=gain)
        for name, controller in (("admittance", ForceAdaptation(settings, DT)),
                                 ("learned profile", ForceProfileLearning(settings, DT, PERIOD))):
            force = wavy_contact(controller, DT, PERIOD, periods)
            out[f"{name}, gain {gain}"] = period_force_errors(force, DT, 0.0, PERIOD, 18.0, smoothing=0.0).tolist()
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_save_argument(parser)
    args = parser.parse_args()
    tilts = np.vstack([[0.0, 0.0], np.random.default_rng(0).uniform(-0.15, 0.15, size=(8, 2))])
    controllers = [(f"{name}, gain {gain}", gain, flag) for gain in (0.02, 0.004)
                   for name, flag in (("admittance", False), ("learned profile", True))]

    def make(gain: float, flag: bool, **kwargs) -> gym.Env:
        return gym.make(ENV_ID, n_periods=10.0, force_learning=flag, admittance_gain=gain, **kwargs)

    envs = {name: make(gain, flag) for name, gain, flag in controllers}
    curved = str(curved_table_scene(results_dir(False)))
    curved_envs = {name: make(gain, flag, xml_file=curved) for name, gain, flag in controllers}
    tap = _TraceTap()
    wipe_env_module.simulate_wipe = tap
    try:
        rows = [{"controller": name, **episode(env, tilt, tap)} for tilt in tilts for name, env in envs.items()]
        curved_rows = [{"controller": name, **episode(env, np.zeros(2), tap)} for name, env in curved_envs.items()]
    finally:
        wipe_env_module.simulate_wipe = tap.original
    print(f"{'tilt (roll, pitch) rad':>22} {'controller':<26} {'500 Hz error per period (N): 1st ... 10th':<52} "
          f"{'h1 contact/wrist/diff':>22} {'coverage':>8}")
    for row in rows:
        text = " ".join(f"{v:.2f}" for v in row["period_errors"])
        label = f"({row['tilt'][0]:+.3f}, {row['tilt'][1]:+.3f})"
        harmonics = f"{row['contact_h1']:.2f}/{row['wrist_h1']:.2f}/{row['difference_h1']:.2f}"
        print(f"{label:>22} {row['controller']:<26} {text:<52} {harmonics:>22} {row['coverage']:>8.3f}")
    summary = {}
    for name in envs:
        group = [r for r in rows if r["controller"] == name]
        errors = np.array([r["period_errors"] for r in group])
        summary[name] = {"mean_error_per_period": errors.mean(axis=0).tolist(),
                         "tilted_mean_error_per_period": errors[1:].mean(axis=0).tolist(),
                         "worst_last_period": float(errors[:, -1].max()),
                         "contact_h1": float(np.mean([r["contact_h1"] for r in group])),
                         "wrist_h1": float(np.mean([r["wrist_h1"] for r in group])),
                         "difference_h1": float(np.mean([r["difference_h1"] for r in group])),
                         "mean_coverage": float(np.mean([r["coverage"] for r in group])),
                         "all_valid": all(r["valid"] and not r["unstable"] for r in group)}
        m = summary[name]
        print(f"{name:<26} mean over 9 tables: " + " ".join(f"{v:.2f}" for v in m["mean_error_per_period"])
              + f"  h1 {m['contact_h1']:.2f}/{m['wrist_h1']:.2f}/{m['difference_h1']:.2f}"
              + f"  coverage {m['mean_coverage']:.3f}")
    print("curved table (crown 6 cm, not tilted):")
    for row in curved_rows:
        print(f"  {row['controller']:<26} " + " ".join(f"{v:.2f}" for v in row["period_errors"])
              + f"  h1 {row['contact_h1']:.2f}/{row['wrist_h1']:.2f}/{row['difference_h1']:.2f}"
              + f"  coverage {row['coverage']:.3f}  valid {row['valid'] and not row['unstable']}")
    wavy = synthetic()
    print("synthetic wavy contact, error per period (N):")
    for name, errors in wavy.items():
        print(f"  {name:<26} " + " ".join(f"{v:.3f}" for v in errors))
    results = results_dir(args.save) / NAME
    results.write_text(json.dumps({"rows": rows, "summary": summary, "curved": curved_rows, "synthetic": wavy},
                                   indent=1))
    print(f"wrote {results}")


if __name__ == "__main__":
    main()
