"""Memory of long rollouts: peak traced allocation of ``RhythmicDMP.rollout`` and of the online stepper.

Setting: 3 DoF, N = M = 40 (D = 80 basis functions), 1 kHz. The forcing term is evaluated in blocks of
``rdmp_gym.dmp.basis.FORCING_BLOCK`` samples; the "unblocked" column sets the block to the whole rollout
(the behaviour before blocks). Target: the rollout's peak grows like its ``[T, d]`` output (a constant
factor), not like the ``[T, D]`` activations; the stepper's memory does not grow with T.
Peaks are measured with ``tracemalloc`` (numpy's allocations are traced). Prints a table; writes
benchmarks/results/memory.json.

    python benchmarks/bench_memory.py
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import json
import platform
import tracemalloc
from collections.abc import Callable

import numpy as np
from output import add_save_argument, results_dir

from rdmp_gym import RhythmicDMP, wiping_demonstration
from rdmp_gym.dmp import basis

RATE = 1000.0


def peak_mb(function: Callable[[], object]) -> float:
    """Peak traced allocation (MB) while ``function`` runs."""
    tracemalloc.start()
    try:
        function()
        return tracemalloc.get_traced_memory()[1] / 1e6
    finally:
        tracemalloc.stop()


def stepper_peak(dmp: RhythmicDMP, seconds: float) -> float:
    def run() -> None:
        stepper = dmp.start(1.0 / RATE)
        for _ in range(int(seconds * RATE)):
            stepper.step()
    return peak_mb(run)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_save_argument(parser)
    RESULTS = results_dir(parser.parse_args().save) / "memory.json"
    dmp = RhythmicDMP.fit(wiping_demonstration(1, rng=0), n_periodic=40, n_transient=40)
    blocked = basis.FORCING_BLOCK
    rows = []
    for seconds in (60.0, 600.0, 3600.0):
        t = np.arange(0.0, seconds, 1.0 / RATE)
        output = t.size * dmp.n_dims * 8 / 1e6
        row = {"seconds": seconds, "samples": int(t.size), "output_mb": output,
               "rollout_peak_mb": peak_mb(lambda t=t: dmp.rollout(t))}
        if seconds <= 600.0:        # the unblocked 1 h rollout needs about 6 GB: not run here
            basis.FORCING_BLOCK = 1 << 40
            row["unblocked_peak_mb"] = peak_mb(lambda t=t: dmp.rollout(t))
            basis.FORCING_BLOCK = blocked
        if seconds <= 600.0:
            row["stepper_peak_mb"] = stepper_peak(dmp, seconds / 10.0)
            row["stepper_seconds"] = seconds / 10.0
        rows.append(row)
    print(f"{'rollout':>8} {'samples':>9} {'output MB':>10} {'peak MB':>9} {'peak/output':>12} "
          f"{'unblocked MB':>13} {'stepper s':>10} {'stepper MB':>11}")
    for row in rows:
        print(f"{row['seconds']:>7.0f}s {row['samples']:>9} {row['output_mb']:>10.1f} {row['rollout_peak_mb']:>9.1f} "
              f"{row['rollout_peak_mb'] / row['output_mb']:>12.1f} {row.get('unblocked_peak_mb', float('nan')):>13.1f} "
              f"{row.get('stepper_seconds', float('nan')):>10.0f} {row.get('stepper_peak_mb', float('nan')):>11.2f}")
    RESULTS.write_text(json.dumps({"setting": "3 DoF, N = M = 40, 1 kHz, tracemalloc peaks", "block": blocked,
                                   "machine": platform.machine(), "python": platform.python_version(),
                                   "numpy": np.__version__, "rows": rows}, indent=2) + "\n")
    print(f"wrote {RESULTS}")


if __name__ == "__main__":
    main()
