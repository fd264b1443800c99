"""Following an external rhythm: lock-in after a frequency step, adaptive vs fixed frequency.

A partner's hand (x of a 5 cm circle plus a 1 cm second harmonic and 1 mm noise, seeds 0..4) runs in phase
with the style-1 wiping DMP (period 1.5 s), then its frequency steps by +-30 % at t = 10 s. The DMP follows
it through :class:`rdmp_gym.dmp.frequency.AdaptiveFrequencyStepper` (K = K_Omega = 2/s, k_phi = 1/s, 500 Hz) or
runs at its fixed frequency. Lock-in: the time after the step from which the frequency the DMP follows stays
within 2 % of the partner's and the phase relation within 0.1 rad of its value before the step. Steady phase
error: RMS over the last 5 s of the change of that relation (and of the absolute phase difference).

    python benchmarks/bench_rhythm.py [--save]
"""

from __future__ import annotations

import argparse
import json

import numpy as np
from output import add_save_argument, results_dir

from rdmp_gym import RhythmicDMP, wiping_demonstration
from rdmp_gym.dmp.frequency import follow_rhythm

NAME = "rhythm.json"
DT, DURATION, STEP = 2e-3, 30.0, 10.0


def partner(dmp: RhythmicDMP, factor: float, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    t = np.arange(round(DURATION / DT)) * DT
    omega = np.where(t < STEP, dmp.canonical.omega, factor * dmp.canonical.omega)
    psi = dmp.transients[0].phi0 + np.concatenate([[0.0], np.cumsum(omega[:-1]) * DT])
    noise = 1e-3 * np.random.default_rng(seed).standard_normal(t.size)
    return t, omega, psi, 0.05 * np.cos(psi) + 0.01 * np.cos(2.0 * psi + 0.3) + noise


def wrap(angle: np.ndarray) -> np.ndarray:
    return np.angle(np.exp(1j * angle))


def measure(t: np.ndarray, omega: np.ndarray, psi: np.ndarray, phase: np.ndarray, frequency: np.ndarray) -> dict:
    error = wrap(phase - psi)
    before = error[(t > STEP - 4.0) & (t < STEP)].mean()
    change = wrap(error - before)
    locked = (np.abs(change) < 0.1) & (np.abs(frequency / omega - 1.0) < 0.02)
    unlocked = np.flatnonzero((t >= STEP) & ~locked)
    lock = 0.0 if unlocked.size == 0 else float(t[unlocked[-1]] + DT - STEP)
    last = t > DURATION - 5.0
    return {"lock_in_s": lock if lock < DURATION - STEP - 5.0 else None,
            "steady_change_rms": float(np.sqrt(np.mean(change[last] ** 2))),
            "steady_abs_rms": float(np.sqrt(np.mean(error[last] ** 2))),
            "offset_before": float(before)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_save_argument(parser)
    args = parser.parse_args()
    dmp = RhythmicDMP.fit(wiping_demonstration(1, rng=0))      # library defaults
    rows = []
    for factor in (1.3, 0.7):
        for seed in range(5):
            t, omega, psi, u = partner(dmp, factor, seed)
            out = follow_rhythm(dmp, u, DT)
            acceleration = np.gradient(out["yd"], DT, axis=0)
            reference = np.abs(np.gradient(np.gradient(dmp.rollout(t), DT, axis=0), DT, axis=0)[t > 5.0]).max()
            rows.append({"model": "adaptive", "factor": factor, "seed": seed,
                         **measure(t, omega, psi, out["phase"], out["frequency"]),
                         "peak_acc_after_over_expected": float(np.abs(acceleration[t > STEP]).max()
                                                               / (reference * factor**2))})
            fixed_phase = dmp.transients[0].phi0 + dmp.canonical.omega * t
            rows.append({"model": "fixed", "factor": factor, "seed": seed,
                         **measure(t, omega, psi, fixed_phase, np.full(t.size, dmp.canonical.omega))})
    print(f"{'model':<9} {'step':>5} {'lock-in s (mean, max)':>22} {'steady change rad':>17} "
          f"{'steady |error| rad':>18} {'peak acc / f^2':>14}")
    summary = {}
    for model in ("adaptive", "fixed"):
        for factor in (1.3, 0.7):
            group = [r for r in rows if r["model"] == model and r["factor"] == factor]
            locks = [r["lock_in_s"] for r in group]
            lock_text = ("never" if any(v is None for v in locks)
                         else f"{np.mean(locks):.2f}, {np.max(locks):.2f}")
            change = float(np.mean([r["steady_change_rms"] for r in group]))
            absolute = float(np.mean([r["steady_abs_rms"] for r in group]))
            peak = max(r.get("peak_acc_after_over_expected", float("nan")) for r in group)
            summary[f"{model}/{factor}"] = {"lock_in": lock_text, "steady_change_rms": change,
                                            "steady_abs_rms": absolute, "peak_acc_ratio": peak}
            print(f"{model:<9} {factor - 1:>+5.0%} {lock_text:>22} {change:>17.3f} {absolute:>18.3f} {peak:>14.2f}")
    results = results_dir(args.save) / NAME
    results.write_text(json.dumps({"rows": rows, "summary": summary}, indent=1))
    print(f"wrote {results}")


if __name__ == "__main__":
    main()
