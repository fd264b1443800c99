"""Fidelity of the rhythmic DMP on the four wiping styles, against the classic periodic DMP.

Relative RMSE (Euclidean error over the signal's largest range) of the transient part and of the
periodic part, against the noiseless signal, for N = M in 10..40, LWR and ridge. Target at N = M = 40:
periodic < 1 %, transient < 2 %, every style. Prints a table; writes benchmarks/results/fidelity.json.

    python benchmarks/bench_fidelity.py [--seed 0]
"""

from __future__ import annotations

import argparse
import json

import numpy as np
from output import add_save_argument, results_dir

from rdmp_gym import PeriodicDMP, RhythmicDMP, segment, wiping_demonstration

SIZES = (10, 14, 20, 27, 35, 40)


def relative_rmse(Y: np.ndarray, reference: np.ndarray, mask: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.sum((Y - reference) ** 2, axis=1)[mask])) / np.ptp(reference, axis=0).max())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0)
    add_save_argument(parser)
    args = parser.parse_args()
    RESULTS = results_dir(args.save) / "fidelity.json"
    rows = []
    for style in (1, 2, 3, 4):
        demo = wiping_demonstration(style, rng=args.seed + style)
        seg = segment(demo)
        clean = demo.truth.clean
        transient = demo.t - demo.t[0] < demo.truth.transient_length

        def record(model: str, method: str, n: int, Y: np.ndarray, style: int = style,
                   clean: np.ndarray = clean, transient: np.ndarray = transient) -> None:
            rows.append({"style": style, "model": model, "method": method, "n": n,
                         "transient_rmse": relative_rmse(Y, clean, transient),
                         "periodic_rmse": relative_rmse(Y, clean, ~transient)})

        for method in ("lwr", "ridge"):
            for n in SIZES:
                record("rhythmic+transient", method, n, RhythmicDMP.fit(demo, n, n, method, segmentations=[seg])
                       .rollout(demo.t))
            record("classic periodic", method, 40, PeriodicDMP.fit(demo, 40, method, segmentation=seg).rollout(demo.t))
        rows.append({"style": style, "segmentation": {"period": seg.period, "true_period": demo.truth.period,
                                                      "transient_length": seg.transient_length,
                                                      "true_transient_length": demo.truth.transient_length}})

    print(f"{'style':>5} {'model':<20} {'method':<6} {'N=M':>4} {'transient %':>12} {'periodic %':>11}")
    for row in rows:
        if "model" in row:
            print(f"{row['style']:>5} {row['model']:<20} {row['method']:<6} {row['n']:>4} "
                  f"{100 * row['transient_rmse']:>12.3f} {100 * row['periodic_rmse']:>11.3f}")
    best = [r for r in rows if r.get("model") == "rhythmic+transient" and r["n"] == 40]
    verdict = {m: all(r["periodic_rmse"] < 0.01 and r["transient_rmse"] < 0.02 for r in best if r["method"] == m)
               for m in ("lwr", "ridge")}
    print(f"targets at N = M = 40 (periodic < 1 %, transient < 2 %, all styles): {verdict}")
    RESULTS.write_text(json.dumps({"rows": rows, "targets_met": verdict}, indent=1))
    print(f"wrote {RESULTS}")


if __name__ == "__main__":
    main()
