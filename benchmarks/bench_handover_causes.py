"""Why the transient rippled before the hand-over: the tested causes, each with its number, on the 12 C2 joins of
``bench_fidelity.py`` (seed 0).

Per join:

* ``capacity``: the least acceleration error over the transient that ANY weights and start state give on the fitted
  basis (noise-free samples at 500 Hz, the true T; least squares on the rollout's acceleration, which is linear in
  both), with the fade before T (:data:`rdmp_gym.dmp.fitting.FADE_BEFORE_T`) and with the defaults (fade after T). A
  large value is a limit of what the mixture (5) can express, which no regression and no noise level can lift.
* ``true T``: the fade-before-T fit and the default fit given the true T and period instead of the segmentation's
  estimate (the estimated T, and its error).
* ``clean``: the default fit of noise-free samples (its error is the fit's bias; the rest is noise), and the same
  without the smoothness and ridge penalties (what is left is the basis's).
* centre timing: the time spacing of the transient centres along the canonical path and the spread of their
  half-height widths in time (equal spacing in time, or not).
* the start: the noise-free, penalty-free fit's acceleration error over the first 0.1 s with the first transient
  centre at the start and one spacing before it (the normalised mixture is one-sided at its first centre).
* ceilings on the noisy samples, each with its penalty chosen knowing the truth: ``best penalty``, the least
  transient acceleration error of the fit over the transient smoothness (:data:`ORACLE_SMOOTHNESS`, the periodic one
  by cross-validation) and the ridge (:data:`ORACLE_RIDGE`), with that fit's jerk and off-path figures; and
  ``best smoother``, a quintic P-spline of the raw samples (a knot at each sample, differences of order
  :data:`SMOOTHER_ORDERS` penalised by :data:`SMOOTHER_PENALTIES`) over ``[0.3 s, T)`` (it does not know that the
  start is at rest), beside the default fit's error over the same span. Low values would mean the defaults'
  penalty choice is what limits a join.

Prints the table; writes benchmarks/results/handover_causes.json.

    python benchmarks/bench_handover_causes.py [--seed 0] [--signals 12] [--save]
"""

from __future__ import annotations

import argparse
import json

import numpy as np
from output import add_save_argument, results_dir
from scipy.interpolate import BSpline

from rdmp_gym import RhythmicDMP, segment
from rdmp_gym.dmp.fitting import FADE_BEFORE_T, fit_rhythmic, trajectory_design
from rdmp_gym.signals.segmentation import Segmentation
from rdmp_gym.synthetic.smoothness import draw_test_demonstrations, handover_figures, motion_metrics

RATE = 500.0
ORACLE_SMOOTHNESS = tuple(float(value) for value in np.logspace(-3.0, 1.0, 9))
ORACLE_RIDGE = (1e-4, 1e-5, 1e-6)
SMOOTHER_PENALTIES = tuple(float(value) for value in np.logspace(-2.0, 12.0, 29))
SMOOTHER_ORDERS = (2, 3, 4, 5)
SMOOTHER_FROM = 0.3


def true_segmentation(signal) -> Segmentation:
    return Segmentation(signal.period, signal.transient_length, signal.anchor)


def second_derivative(values: np.ndarray, dt: float) -> np.ndarray:
    return np.gradient(np.gradient(values, dt, axis=0, edge_order=2), dt, axis=0, edge_order=2)


def capacity(signal, settings: dict) -> float:
    """The least transient acceleration error (over the true RMS) of any weights and start on the fitted basis."""
    clean = signal.demonstration(signal.transient_length + 5.0, rate=RATE, noise=0.0)
    parts = fit_rhythmic(clean, segmentations=[true_segmentation(signal)], **settings)
    start = parts.transients[0]
    responses, columns, samples = trajectory_design(parts.canonical, parts.basis, [clean], [(start.phi0, start.r0)],
                                                    [start.length], parts.anchor, parts.alpha_z, 1)
    design = second_derivative(np.concatenate([responses[0], columns[0]], axis=1), clean.dt)
    target = second_derivative(samples[0], clean.dt)
    residual = design @ np.linalg.lstsq(design, target, rcond=None)[0] - target
    transient = clean.t < signal.transient_length
    acceleration = signal.derivatives(clean.t)[2]
    return float(np.sqrt(np.mean(np.sum(residual[transient] ** 2, axis=1))
                         / np.mean(np.sum(acceleration[transient] ** 2, axis=1))))


def centre_timing(dmp: RhythmicDMP) -> tuple[float, float, float]:
    """Relative spread of the transient centres' time spacing along the path, and the smallest and largest
    half-height width (s) of the transient functions in time."""
    start = dmp.transients[0]
    t = np.arange(-0.2, start.length + 1.0, 1e-3)
    phi, r = dmp.canonical.state(t, start.phi0, start.r0)
    raw = dmp.basis.activations(phi, r)[:, dmp.basis.n_periodic:]
    peaks = t[np.argmax(raw, axis=0)]
    widths = [float(np.ptp(t[column > 0.5 * column.max()])) for column in raw.T[1:-1]]
    spacing = np.diff(peaks)
    return float(np.std(spacing) / np.mean(spacing)), min(widths), max(widths)


def start_error(signal, lead: float) -> float:
    """RMS acceleration error (m/s^2) over the first 0.1 s of the noise-free, penalty-free fit."""
    clean = signal.demonstration(signal.transient_length + 5.0, rate=RATE, noise=0.0)
    dmp = RhythmicDMP.fit(clean, segmentations=[true_segmentation(signal)], smoothness=0.0, regularization=1e-10,
                          transient_lead=lead)
    t = np.arange(0.0, 0.3, 1e-3)
    error = second_derivative(dmp.rollout(t), 1e-3) - signal.derivatives(t)[2]
    return float(np.sqrt(np.mean(np.sum(error[(t > 0.005) & (t < 0.1)] ** 2, axis=1))))


def transient_error(signal, Y: np.ndarray, t: np.ndarray, begin: float = 0.0) -> float:
    """Acceleration error of ``Y [len(t), d]`` over ``[begin, T)`` relative to the truth's RMS there."""
    position, _, acceleration, jerk = signal.derivatives(t)
    span = (t >= begin) & (t < signal.transient_length)
    return motion_metrics(Y, (position, acceleration, jerk), t[1] - t[0], span)["acceleration"]


def best_penalty(signal, demo) -> dict:
    """The fit of least transient acceleration error over :data:`ORACLE_SMOOTHNESS` x :data:`ORACLE_RIDGE`."""
    t = np.arange(0.0, signal.transient_length + 0.5, 1e-3)
    fits = ((RhythmicDMP.fit(demo, smoothness=("auto", value), regularization=ridge), value, ridge)
            for value in ORACLE_SMOOTHNESS for ridge in ORACLE_RIDGE)
    dmp, value, ridge = min(fits, key=lambda fit: transient_error(signal, fit[0].rollout(t), t))
    figures = handover_figures(signal, dmp, demo.duration)
    return {"smoothness": value, "ridge": ridge, **{key: figures[key] for key in
                                                    ("transient acceleration", "transient jerk", "off-path peak")}}


def best_smoother(signal, demo) -> tuple[float, int]:
    """The least acceleration error over ``[SMOOTHER_FROM, T)`` of a quintic P-spline of the raw samples, over the
    penalised difference orders :data:`SMOOTHER_ORDERS` and the penalties :data:`SMOOTHER_PENALTIES`; and its order."""
    knots = np.concatenate([[demo.t[0]] * 5, demo.t, [demo.t[-1]] * 5])
    design = BSpline.design_matrix(demo.t, knots, 5).toarray()
    t = np.arange(0.0, signal.transient_length, 1e-3)
    acceleration = signal.derivatives(t)[2]
    span = t >= SMOOTHER_FROM
    errors = []
    for order in SMOOTHER_ORDERS:
        differences = np.diff(np.eye(design.shape[1]), order, axis=0)
        for penalty in SMOOTHER_PENALTIES:
            spline = BSpline(knots, np.linalg.solve(design.T @ design + penalty * differences.T @ differences,
                                                    design.T @ demo.Y), 5)
            error = spline.derivative(2)(t) - acceleration
            errors.append((float(np.sqrt(np.sum(error[span] ** 2) / np.sum(acceleration[span] ** 2))), order))
    return min(errors)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--signals", type=int, default=12)
    add_save_argument(parser)
    args = parser.parse_args()
    rows = []
    for index, (signal, demo) in enumerate(draw_test_demonstrations(np.random.default_rng(args.seed), args.signals,
                                                                     "quintic")):
        estimated = segment(demo)
        before = RhythmicDMP.fit(demo, segmentations=[estimated], **FADE_BEFORE_T)
        truth = true_segmentation(signal)
        given = RhythmicDMP.fit(demo, segmentations=[truth], **FADE_BEFORE_T)
        clean = signal.demonstration(demo.duration, rate=100.0, noise=0.0)
        spread, narrowest, widest = centre_timing(before)
        grid = np.arange(0.0, signal.transient_length + 0.5, 1e-3)
        smoother, order = best_smoother(signal, demo)
        default = RhythmicDMP.fit(demo)
        rows.append({
            "join": index, "T": signal.transient_length, "T estimated": estimated.transient_length,
            "capacity before": capacity(signal, FADE_BEFORE_T), "capacity default": capacity(signal, {}),
            "before": handover_figures(signal, before, demo.duration)["transient acceleration"],
            "before, true T": handover_figures(signal, given, demo.duration)["transient acceleration"],
            "default": handover_figures(signal, default, demo.duration)["transient acceleration"],
            "default, true T": handover_figures(signal, RhythmicDMP.fit(demo, segmentations=[truth]),
                                                demo.duration)["transient acceleration"],
            "default, clean": handover_figures(signal, RhythmicDMP.fit(clean), demo.duration)["transient acceleration"],
            "default, clean, no penalty": handover_figures(signal, RhythmicDMP.fit(
                clean, smoothness=0.0, regularization=1e-10), demo.duration)["transient acceleration"],
            "spacing spread": spread, "width min": narrowest, "width max": widest,
            "start error, lead 0": start_error(signal, 0.0), "start error, lead 1": start_error(signal, 1.0),
            "best penalty": best_penalty(signal, demo), "best smoother, from 0.3 s": smoother,
            "best smoother order": order,
            "default, from 0.3 s": transient_error(signal, default.rollout(grid), grid, SMOOTHER_FROM)})
    print(f"{'join':>4} {'T / est (s)':>12} {'capacity % before/default':>26} {'before % est/true T':>20} "
          f"{'default % noisy/true T/clean/no penalty':>39} {'spacing spread':>14} {'width s min/max':>16} "
          f"{'start m/s2 lead 0/1':>20} {'best penalty % (jerk x, off-path x)':>36} "
          f"{'from 0.3 s: default/best smoother % (order)':>40}")
    for row in rows:
        print(f"{row['join']:4d} {row['T']:5.2f}/{row['T estimated']:5.2f} "
              f"{100 * row['capacity before']:17.1f}/{100 * row['capacity default']:5.1f} "
              f"{100 * row['before']:14.1f}/{100 * row['before, true T']:5.1f} "
              f"{100 * row['default']:21.1f}/{100 * row['default, true T']:5.1f}/{100 * row['default, clean']:5.1f}/"
              f"{100 * row['default, clean, no penalty']:5.1f} "
              f"{row['spacing spread']:14.1e} "
              f"{row['width min']:9.3f}/{row['width max']:5.3f} "
              f"{row['start error, lead 0']:14.2f}/{row['start error, lead 1']:5.2f} "
              f"{_best_penalty_cell(row['best penalty']):>36} "
              f"{100 * row['default, from 0.3 s']:27.1f}/{100 * row['best smoother, from 0.3 s']:5.1f} "
              f"({row['best smoother order']})")
    path = results_dir(args.save) / "handover_causes.json"
    path.write_text(json.dumps({"seed": args.seed, "rows": rows}, indent=1))
    print(f"wrote {path}")


def _best_penalty_cell(best: dict) -> str:
    return (f"{100 * best['transient acceleration']:.1f} ({best['transient jerk']:.2f}, {best['off-path peak']:.2f}) "
            f"s {best['smoothness']:.2g} r {best['ridge']:.0e}")


if __name__ == "__main__":
    main()
