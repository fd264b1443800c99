"""Fidelity of the rhythmic DMP on the four wiping styles and on own smooth test signals, against the
classic periodic DMP: position, acceleration and jerk at 1 kHz.

Per part (transient / periodic): position RMSE over the signal's largest range, acceleration RMSE over
the RMS of the true acceleration, integrated squared jerk over the true signal's, peak acceleration over
the true peak. References: the noiseless built-in styles at 1 kHz (derivatives by central differences) and
:class:`rdmp_gym.synthetic.smoothness.SmoothTestSignal` (analytic derivatives). Models: the defaults
(``trajectory`` fit, smooth start), :data:`rdmp_gym.dmp.fitting.FADE_BEFORE_T` (the environments' fit), the paper's
settings (:data:`rdmp_gym.dmp.fitting.PAPER_SETTINGS`, LWR and ridge, rolled out from the demonstrated start as in the
paper), and the classic periodic DMP.
Targets (library defaults): acceleration <= 10 % / 15 % (periodic / transient), jerk <= 2x, peak <= 1.3x,
position < 0.3 % / 0.8 %. Prints a table; writes benchmarks/results/fidelity.json.

The hand-over: signals whose start is a quintic from rest joined to the orbit at T with matching position, velocity
and acceleration (C2, at an arbitrary phase of an orbit of 1-3 harmonics; every second one with a bump in the
approach; :func:`rdmp_gym.synthetic.smoothness.draw_test_demonstrations`), fitted with the defaults (the families fade
over the ``t_f`` after T, M = 44 transient centres from two spacings before the start, the smoothness penalty relative
to the pattern and relaxed about T, each family's smoothness and the start velocity's pull towards rest chosen by
generalised cross-validation), with one fixed smoothness 0.3 for both families, with a free start velocity, the full
penalty at T and M = 40 from one spacing before the start ("free start, M 40"), and with
:data:`rdmp_gym.dmp.fitting.FADE_BEFORE_T` (the fade before T, as the environments fit). Per signal
(:func:`rdmp_gym.synthetic.smoothness.handover_figures`): acceleration error over the transient and the periodic part,
the worst 0.2 s window of acceleration error over the signal's RMS acceleration (and where it starts, relative to T),
jerk ratios, position errors, and the largest peak acceleration from canonical starts off the encoded path over the
demonstration's peak; targets in :data:`rdmp_gym.synthetic.smoothness.HANDOVER_TARGETS` (transient acceleration <= 10 %,
periodic <= 5 %, window <= 20 %, jerk <= 1.5x, position < 0.8 % / 0.3 %, off-path peak <= 3x). The figure
``handover.png`` shows the acceleration about T on the three signals that the fade before T reproduces worst.

Prints the tables; writes benchmarks/results/fidelity.json and handover.png.

    python benchmarks/bench_fidelity.py [--seed 0] [--signals 6] [--handover-signals 12]
"""

from __future__ import annotations

import argparse
import json

import numpy as np
from output import add_save_argument, results_dir

from rdmp_gym import PeriodicDMP, RhythmicDMP, segment, wiping_demonstration
from rdmp_gym.dmp.fitting import FADE_BEFORE_T, PAPER_SETTINGS
from rdmp_gym.synthetic.smoothness import (
    draw_test_demonstrations,
    finite_derivatives,
    handover_figures,
    handover_misses,
    motion_metrics,
    random_test_signal,
)

DT = 1e-3
MODELS = {"default": ({}, True), "fade before T": (FADE_BEFORE_T, True), "paper lwr": (PAPER_SETTINGS, False),
          "paper ridge": ({**PAPER_SETTINGS, "method": "ridge"}, False)}
FREE_START = {"n_transient": 40, "transient_lead": 1.0, "start_prior": 0.0, "join_width": 0.0}
HANDOVER_MODELS = {"fade before T": FADE_BEFORE_T, "smoothness 0.3": {"smoothness": 0.3},
                   "free start, M 40": FREE_START, "default": {}}


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


def handover_benchmark(seed: int, n_signals: int, folder) -> list[dict]:
    """Fit each hand-over signal with each of ``HANDOVER_MODELS``, print the table, draw ``handover.png``."""
    rows, traces = [], []
    for index, (signal, demo) in enumerate(draw_test_demonstrations(np.random.default_rng(seed), n_signals,
                                                                     "quintic")):
        name = (f"join {index} (p {signal.period:.2f} s, {signal.cos_coefficients.shape[0]} harm., "
                f"T {signal.transient_length:.2f} s{', bump' if np.any(signal.detour) else ''})")
        t = np.arange(0.0, demo.duration + 1e-9, DT)
        _, _, acceleration, _ = signal.derivatives(t)
        accelerations = {}
        for model, settings in HANDOVER_MODELS.items():
            dmp = RhythmicDMP.fit(demo, **settings)
            figures = handover_figures(signal, dmp, demo.duration, DT)
            rows.append({"case": name, "model": model, **figures, "misses": handover_misses(figures)})
            accelerations[model] = finite_derivatives(dmp.rollout(t), DT)[1]
        traces.append((name, signal, accelerations, acceleration))
    print(f"\n{'hand-over case':<44} {'model':<16} {'acc % tr/per':>13} {'window % (from T)':>18} "
          f"{'jerk x tr/all':>14} {'pos % tr/per':>13} {'off-path x':>10}  misses")
    for row in rows:
        print(f"{row['case']:<44} {row['model']:<16} {100 * row['transient acceleration']:6.1f}/"
              f"{100 * row['periodic acceleration']:5.1f} {100 * row['worst window']:8.1f} "
              f"({row['worst window from']:+.2f} s) "
              f"{row['transient jerk']:7.2f}/{row['jerk']:5.2f} {100 * row['transient position']:6.2f}/"
              f"{100 * row['periodic position']:5.3f} {row['off-path peak']:10.2f}  {', '.join(row['misses']) or '-'}")
    for model in HANDOVER_MODELS:
        mine = [row for row in rows if row["model"] == model]
        print(f"{model}: transient acceleration {100 * min(r['transient acceleration'] for r in mine):.1f}-"
              f"{100 * max(r['transient acceleration'] for r in mine):.1f} % (median "
              f"{100 * np.median([r['transient acceleration'] for r in mine]):.1f} %), worst window up to "
              f"{100 * max(r['worst window'] for r in mine):.1f} %, every target met on "
              f"{sum(not r['misses'] for r in mine)} of {len(mine)}")
    draw_handover(traces, rows, folder / "handover.png")
    return rows


def draw_handover(traces: list, rows: list[dict], path) -> None:
    """Acceleration about T, truth against each model, on the three signals the fade before T does worst."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    before = {row["case"]: row["transient acceleration"] for row in rows if row["model"] == "fade before T"}
    worst = sorted(traces, key=lambda trace: -before[trace[0]])[:3]
    figure, axes = plt.subplots(len(worst), 1, figsize=(9, 2.8 * len(worst)), squeeze=False)
    for axis, (name, signal, accelerations, truth) in zip(axes[:, 0], worst, strict=True):
        t = np.arange(truth.shape[0]) * DT
        shown = (t > signal.transient_length - 1.0) & (t < signal.transient_length + 0.6)
        dim = int(np.argmax(np.sum((accelerations["fade before T"] - truth)[shown] ** 2, axis=0)))
        axis.plot(t[shown], truth[shown, dim], color="black", lw=2.0, label="true")
        for model, acceleration in accelerations.items():
            axis.plot(t[shown], acceleration[shown, dim], lw=1.0, label=model)
        axis.axvline(signal.transient_length, color="grey", ls="--", lw=0.8)
        axis.set_title(f"{name}, dimension {dim}", fontsize=9)
        axis.set_ylabel("acceleration (m/s²)")
    axes[0, 0].legend(fontsize=8)
    axes[-1, 0].set_xlabel("time (s); dashed: T, where the start joins the orbit")
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)
    print(f"wrote {path}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--signals", type=int, default=6)
    parser.add_argument("--handover-signals", type=int, default=12)
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
    handover = handover_benchmark(args.seed, args.handover_signals, RESULTS.parent)
    verdict["handover"] = {row["case"]: row["misses"] for row in handover if row["model"] == "default"}
    print(f"hand-over signals missing a target (defaults): "
          f"{ {case: misses for case, misses in verdict['handover'].items() if misses} }")
    RESULTS.write_text(json.dumps({"seed": args.seed, "rows": rows, "handover": handover, "targets": verdict},
                                  indent=1))
    print(f"wrote {RESULTS}")


if __name__ == "__main__":
    main()
