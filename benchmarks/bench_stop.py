"""The end of the movement: how well one DMP reproduces a demonstrated stop.

For the four wiping styles, demonstrations that end (approach, 3 periods, lift off, 1 s at rest; noise
0.3 mm, 100 Hz; seeds 0..4) are segmented and fitted with ``fit_ending``; the stop is requested 1 s before
the demonstrated exit. On the stop (from the true departure to the end, 1 kHz against the noiseless
signal): position error / range (max over dims), acceleration relative RMSE and peak ratio, distance and
speed at the end; and the segmentation's errors. Two periodic fits: the library defaults and a smooth
one (wider periodic basis), because the periodic family is still active at the exit. Bars: position
<= 1 %, acceleration relative RMSE <= 15 %, peak <= 1.3x, rest within 1 mm and 1 mm/s.

    python benchmarks/bench_stop.py [--save]
"""

from __future__ import annotations

import argparse
import json

import numpy as np
from output import add_save_argument, results_dir

from rdmp_gym.dmp.stopping import fit_ending
from rdmp_gym.signals.segmentation import segment_ending
from rdmp_gym.synthetic.demonstrations import ending_demonstration

NAME = "stop.json"
H = 1e-3
FITS = {"default": {}, "smooth": dict(n_periodic=30, periodic_overlap=0.9, smoothing=0.3, regularization=1e-4)}


def evaluate(style: int, seed: int, fit: str) -> dict:
    demo = ending_demonstration(style, rng=seed)
    fine = ending_demonstration(style, rng=seed, rate=1000.0, noise=0.0)
    t_exit = fine.truth.transient_length + 3.0 * fine.truth.period
    seg = segment_ending(demo)
    dmp = fit_ending(demo, segmentation=seg, **FITS[fit])
    acceleration = np.gradient(np.gradient(fine.Y, H, axis=0), H, axis=0)
    y, yd = dmp.rollout(fine.t, stop_at=t_exit - 1.0, return_velocity=True)
    a = np.gradient(yd, H, axis=0)
    stop = fine.t >= t_exit
    return {"style": style, "seed": seed, "fit": fit,
            "position": float(np.max(np.abs(y[stop] - fine.Y[stop]).max(axis=0) / np.ptp(fine.Y, axis=0))),
            "acc_rel_rmse": float(np.sqrt(np.mean((a[stop] - acceleration[stop]) ** 2)
                                          / np.mean(acceleration[stop] ** 2))),
            "acc_peak_ratio": float(np.abs(a[stop]).max() / np.abs(acceleration[stop]).max()),
            "end_distance_mm": float(1e3 * np.linalg.norm(y[-1] - fine.Y[-1])),
            "end_speed_mm_s": float(1e3 * np.linalg.norm(yd[-1])),
            "periodic_end_error_s": float(seg.periodic_end - t_exit),
            "rest_error_s": float(seg.rest_time - (t_exit + 1.5)),
            "goal_error_mm": float(1e3 * np.linalg.norm(seg.goal - fine.Y[-1]))}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_save_argument(parser)
    args = parser.parse_args()
    rows = [evaluate(style, seed, fit) for fit in FITS for style in (1, 2, 3, 4) for seed in range(5)]
    print(f"{'fit':<8} {'style':>5} {'pos % max':>9} {'acc rRMSE max':>13} {'peak max':>8} {'end mm max':>10} "
          f"{'end mm/s max':>12} {'exit lag s':>10} {'rest lead s':>11}")
    summary = {}
    for fit in FITS:
        for style in (1, 2, 3, 4):
            group = [r for r in rows if r["fit"] == fit and r["style"] == style]
            worst = {key: max(r[key] for r in group) for key in
                     ("position", "acc_rel_rmse", "acc_peak_ratio", "end_distance_mm", "end_speed_mm_s")}
            lag = np.mean([r["periodic_end_error_s"] for r in group])
            lead = np.mean([r["rest_error_s"] for r in group])
            summary[f"{fit}/{style}"] = worst
            print(f"{fit:<8} {style:>5} {100 * worst['position']:>9.3f} {worst['acc_rel_rmse']:>13.3f} "
                  f"{worst['acc_peak_ratio']:>8.3f} {worst['end_distance_mm']:>10.3f} {worst['end_speed_mm_s']:>12.2e} "
                  f"{lag:>10.3f} {lead:>11.3f}")
    results = results_dir(args.save) / NAME
    results.write_text(json.dumps({"rows": rows, "worst": summary}, indent=1))
    print(f"wrote {results}")


if __name__ == "__main__":
    main()
