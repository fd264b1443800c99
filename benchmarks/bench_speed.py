"""Speed of the core on one core: fit, one rollout, a batch of 64 rollouts, online steps.

Setting: 3 DoF, N = M = 40, 10 s at 100 Hz. Targets: one rollout < 2 ms, a batch of 64 < 20 ms.
Prints a table (median and best wall time of repeated runs, and the median process CPU time, which
other jobs on a shared machine disturb less; a target is judged on the CPU time); writes
benchmarks/results/speed.json. In "weights + initial cond." every rollout follows its own canonical
path (``rdmp_gym.dmp.batched``).

    python benchmarks/bench_speed.py
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")       # one core, before numpy is imported
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import argparse
import json
import platform
import time
from collections.abc import Callable

import numpy as np
from output import add_save_argument, results_dir

from rdmp_gym import RhythmicDMP, segment, wiping_demonstration


def timed(function: Callable[[], object], repeats: int) -> tuple[float, float, float]:
    """(median wall, best wall, median CPU) seconds over ``repeats`` calls, after one warm-up call."""
    function()
    samples, cpu = [], []
    for _ in range(repeats):
        start, start_cpu = time.perf_counter(), time.process_time()
        function()
        samples.append(time.perf_counter() - start)
        cpu.append(time.process_time() - start_cpu)
    return float(np.median(samples)), float(np.min(samples)), float(np.median(cpu))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_save_argument(parser)
    RESULTS = results_dir(parser.parse_args().save) / "speed.json"
    demo = wiping_demonstration(1, rng=0)
    seg = segment(demo)
    dmp = RhythmicDMP.fit(demo, 40, 40, segmentations=[seg])
    t = np.arange(1000) * 0.01
    groups = ("periodic", "transient", "initial")
    theta = dmp.get_params(groups)
    rng = np.random.default_rng(0)
    weights_only = theta + np.concatenate([rng.normal(0, 5.0, (64, theta.size - 2)), np.zeros((64, 2))], axis=1)
    with_initial = weights_only.copy()
    with_initial[:, -2:] += rng.normal(0, [0.1, 0.5], (64, 2))

    def steps() -> None:
        stepper = dmp.start(0.01)
        for _ in range(1000):
            stepper.step()

    cases = [
        ("segment (period, transient, anchor)", lambda: segment(demo), 10, 1),
        ("fit, ridge (given segmentation)", lambda: RhythmicDMP.fit(demo, 40, 40, segmentations=[seg]), 10, 1),
        ("fit, lwr (given segmentation)", lambda: RhythmicDMP.fit(demo, 40, 40, "lwr", segmentations=[seg]), 10, 1),
        ("rollout 10 s @ 100 Hz, 3 DoF", lambda: dmp.rollout(t), 200, 1),
        ("batch of 64, weights perturbed", lambda: dmp.rollout_batch(weights_only, t, groups), 30, 1),
        ("batch of 64, weights + initial cond.", lambda: dmp.rollout_batch(with_initial, t, groups), 30, 1),
        ("1000 online steps", steps, 5, 1000),
    ]
    targets = {"rollout 10 s @ 100 Hz, 3 DoF": 2e-3, "batch of 64, weights perturbed": 20e-3,
               "batch of 64, weights + initial cond.": 20e-3}
    rows = []
    print(f"{'case':<40} {'median ms':>10} {'best ms':>9} {'CPU ms':>8} {'target ms':>10}  ok")
    for name, function, repeats, per_call in cases:
        median, best, cpu = timed(function, repeats)
        target = targets.get(name)
        row = {"case": name, "median_s": median, "best_s": best, "median_cpu_s": cpu, "target_s": target,
               "met": None if target is None else cpu < target}
        if per_call > 1:
            row["calls_per_s"] = per_call / median
        rows.append(row)
        print(f"{name:<40} {1e3 * median:>10.3f} {1e3 * best:>9.3f} {1e3 * cpu:>8.3f} "
              f"{'' if target is None else f'{1e3 * target:.1f}':>10}  {'' if target is None else row['met']}")
    step_rate = next(r["calls_per_s"] for r in rows if "calls_per_s" in r)
    print(f"online step calls per second: {step_rate:,.0f}")
    # own canonical paths vs one shared path, interleaved (a ratio that the machine's load hardly moves)
    cpu: dict[str, list[float]] = {"shared": [], "own": []}
    for _ in range(15):
        for key, batch in (("shared", weights_only), ("own", with_initial)):
            start = time.process_time()
            dmp.rollout_batch(batch, t, groups)
            cpu[key].append(time.process_time() - start)
    ratio = np.array(cpu["own"]) / np.array(cpu["shared"])
    interleaved = {"median_cpu_s": {key: float(np.median(values)) for key, values in cpu.items()},
                   "ratio_median": float(np.median(ratio)), "ratio_range": [float(ratio.min()), float(ratio.max())]}
    print(f"batch of 64 with perturbed initial conditions / weights only, interleaved CPU time: "
          f"{interleaved['ratio_median']:.2f} (range {ratio.min():.2f}-{ratio.max():.2f}; "
          f"{1e3 * interleaved['median_cpu_s']['own']:.1f} vs {1e3 * interleaved['median_cpu_s']['shared']:.1f} ms)")
    RESULTS.write_text(json.dumps({"machine": platform.processor() or platform.machine(),
                                   "python": platform.python_version(), "rows": rows,
                                   "own_paths_vs_shared_path": interleaved}, indent=1))
    print(f"wrote {RESULTS}")


if __name__ == "__main__":
    main()
