"""Fidelity of the rhythmic DMP on the four wiping styles and on own smooth test signals, against the
classic periodic DMP: position, acceleration and jerk at 1 kHz.

Per part (transient / periodic): position RMSE over the signal's largest range, acceleration RMSE over
the RMS of the true acceleration, integrated squared jerk over the true signal's, peak acceleration over
the true peak. References: the noiseless built-in styles at 1 kHz (derivatives by central differences) and
:class:`rdmp_gym.smoothness.SmoothTestSignal` (analytic derivatives). Models: the defaults
(``trajectory`` fit, smooth start), the paper's settings (:data:`rdmp_gym.dmp.PAPER_SETTINGS`, LWR and ridge,
rolled out from the demonstrated start as in the paper), and the classic periodic DMP.
Targets (library defaults): acceleration <= 10 % / 15 % (periodic / transient), jerk <= 2x, peak <= 1.3x,
position < 0.3 % / 0.8 %. Prints a table; writes benchmarks/results/fidelity.json.

    python benchmarks/bench_fidelity.py [--seed 0] [--signals 6]
"""

from __future__ import annotations

import argparse
import json

import numpy as np
from output import add_save_argument, results_dir

from rdmp_gym import PeriodicDMP, RhythmicDMP, segment, wiping_demonstration
from rdmp_gym.dmp import PAPER_SETTINGS
from rdmp_gym.smoothness import finite_derivatives, motion_metrics, random_test_signal

DT = 1e-3
MODELS = {"default": ({}, True), "paper lwr": (PAPER_SETTINGS, False),
          "paper ridge": ({**PAPER_SETTINGS, "method": "ridge"}, False)}


def cases(seed: int, n_signals: int):
    """(name, demonstration, fine times [T], (position, acceleration, jerk) at 1 kHz, transient length)."""
    for style in (1, 2, 3, 4):
        demo = wiping_demonstration(style, rng=seed + style)
        fine = wiping_demonstration(style, rng=0, rate=1000, noise=0.0)
        _, acceleration, jerk = finite_derivatives(fine.truth.clean, DT)
        yield f"style {style}", demo, fine.t, (fine.truth.clean, acceleration, jerk), demo.truth.transient_length
    rng = np.random.default_rng(seed)
    for index in range(n_signals):
        signal = random_test_signal(rng)
        duration = signal.transient_length + max(6 * signal.period, 5.0)
        demo = signal.demonstration(duration, noise=rng.uniform(3e-4, 5e-4), rng=rng)
        t = np.arange(0.0, duration + 1e-9, DT)
        position, _, acceleration, jerk = signal.derivatives(t)
        name = (f"signal {index} (p {signal.period:.2f} s, {signal.cos_coefficients.shape[0]} harm., "
                f"T {signal.transient_length:.2f} s)")
        yield name, demo, t, (position, acceleration, jerk), signal.transient_length


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--signals", type=int, default=6)
    add_save_argument(parser)
    args = parser.parse_args()
    RESULTS = results_dir(args.save) / "fidelity.json"
    rows = []
    for name, demo, t, reference, length in cases(args.seed, args.signals):
        seg = segment(demo)
        transient = t < length
        rollouts = {model: RhythmicDMP.fit(demo, segmentations=[seg], **settings).rollout(t, start_blend=blend)
                    for model, (settings, blend) in MODELS.items()}
        rollouts["classic periodic"] = PeriodicDMP.fit(demo, segmentation=seg).rollout(t)
        for model, Y in rollouts.items():
            rows.append({"case": name, "model": model,
                         "transient": motion_metrics(Y, reference, DT, transient),
                         "periodic": motion_metrics(Y, reference, DT, ~transient)})
    header = (f"{'case':<38} {'model':<17} {'pos % tr/per':>14} {'acc % tr/per':>15} {'jerk x tr/per':>16} "
              f"{'peak x tr/per':>14}")
    print(header)
    for row in rows:
        tr, pe = row["transient"], row["periodic"]
        print(f"{row['case']:<38} {row['model']:<17} {100 * tr['position']:6.2f}/{100 * pe['position']:6.3f} "
              f"{100 * tr['acceleration']:7.1f}/{100 * pe['acceleration']:6.1f} "
              f"{tr['jerk_ratio']:8.1f}/{pe['jerk_ratio']:6.1f} "
              f"{tr['peak_acceleration_ratio']:6.2f}/{pe['peak_acceleration_ratio']:6.2f}")

    def met(row: dict) -> bool:
        tr, pe = row["transient"], row["periodic"]
        return (pe["position"] < 0.003 and tr["position"] < 0.008 and pe["acceleration"] <= 0.10
                and tr["acceleration"] <= 0.15 and max(tr["jerk_ratio"], pe["jerk_ratio"]) <= 2.0
                and max(tr["peak_acceleration_ratio"], pe["peak_acceleration_ratio"]) <= 1.3)

    defaults = [row for row in rows if row["model"] == "default"]
    verdict = {"styles": all(met(r) for r in defaults if r["case"].startswith("style")),
               "signals": [r["case"] for r in defaults if not r["case"].startswith("style") and not met(r)]}
    print(f"targets met by the defaults on the four styles: {verdict['styles']}; "
          f"own signals missing a target: {verdict['signals']}")
    RESULTS.write_text(json.dumps({"seed": args.seed, "rows": rows, "targets": verdict}, indent=1))
    print(f"wrote {RESULTS}")


if __name__ == "__main__":
    main()
