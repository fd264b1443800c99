"""Where the hand rests: the speed of sampled motion and the thresholds that call it at rest.

Speed is smoothed (Savitzky-Golay over :data:`SPEED_WINDOW`, then a median over 0.3 s: a single bump of noise does
not end a rest). The threshold is relative to the motion's own scale (a share of its typical speed while it
moves), and at least :data:`NOISE_FACTOR` times its speed in its quietest 0.5 s (sensor noise), so a slow drift
at rest and sensor noise pass. Used by the segmentation of whole recordings (the rests around the rhythm) and of
demonstrations that end (the final rest).
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import median_filter

from rdmp_gym.signals.demonstrations import Demonstration
from rdmp_gym.signals.filters import smooth_derivatives

__all__ = ["MIN_REST", "NOISE_FACTOR", "SPEED_WINDOW", "high_level", "motion_speed", "noise_speed", "rest_onset",
           "rest_start", "rest_threshold"]

SPEED_WINDOW = 0.5
"""Smoothing (s) of the speed used for rest (Savitzky-Golay, then a median over 0.3 s)."""

NOISE_FACTOR = 3.0
"""The rest threshold is at least this multiple of the speed in the quietest 0.5 s."""

MIN_REST = 0.3
"""The shortest final rest recognised (s)."""


def motion_speed(demo: Demonstration, window: float = SPEED_WINDOW) -> np.ndarray:
    """Speed ``[L]`` (m/s, norm over the dimensions) of ``demo`` smoothed over ``window`` s (Savitzky-Golay; the
    first and last half window hold the nearest inner value), then the median over 0.3 s (a single bump of noise
    does not end a rest)."""
    speed = np.linalg.norm(smooth_derivatives(demo.Y, demo.dt, window, polyorder=3)[1], axis=1)
    edge = min(round(0.5 * window / demo.dt), (speed.size - 1) // 2)
    if edge > 0:        # the fitted polynomials' ends swing with the noise: the edges take the nearest inner value
        speed[:edge], speed[-edge:] = speed[edge], speed[-edge - 1]
    return median_filter(speed, size=max(round(0.3 / demo.dt) | 1, 3), mode="nearest")


def noise_speed(speed: np.ndarray, dt: float) -> float:
    """The median speed over the quietest 0.5 s of ``speed [L]`` (the noise level, where the hand rests somewhere)."""
    width = max(round(0.5 / dt), 1)
    if speed.size <= width:
        return float(np.median(speed))
    return float(np.min(median_filter(speed, size=width, mode="nearest")))


def high_level(values: np.ndarray) -> float:
    """A robust high level of ``values``: the median of those above half the 98th percentile."""
    top = np.quantile(values, 0.98)
    return float(np.median(values[values >= 0.5 * top]))


def rest_threshold(speed: np.ndarray, dt: float, typical: float, fraction: float) -> float:
    """The speed below which the hand counts as at rest: ``fraction`` of the ``typical`` speed while it moves, or
    :data:`NOISE_FACTOR` times its speed in its quietest 0.5 s (:func:`noise_speed`) where that is higher."""
    return max(fraction * typical, NOISE_FACTOR * noise_speed(speed, dt))


def rest_onset(speed: np.ndarray, threshold: float, dt: float, min_rest: float = MIN_REST) -> int | None:
    """Index from which ``speed [L]`` stays below ``threshold`` to the end, if that lasts ``min_rest`` s; else None."""
    moving = np.flatnonzero(speed >= threshold)
    first = 0 if moving.size == 0 else int(moving[-1]) + 1
    return first if (speed.size - first) * dt >= min_rest else None


def rest_start(demo: Demonstration, fraction: float = 0.05, min_rest: float = MIN_REST) -> int | None:
    """Index from which ``demo`` rests to its end (at least ``min_rest`` s), or ``None``: its speed
    (:func:`motion_speed`) stays below :func:`rest_threshold` with ``fraction`` of its typical speed while moving
    (:func:`high_level`)."""
    speed = motion_speed(demo)
    threshold = rest_threshold(speed, demo.dt, high_level(speed), fraction)
    return rest_onset(speed, threshold, demo.dt, min_rest)
