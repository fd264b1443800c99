"""Smoothness of a commanded motion, computed before simulation: the jerk of a tool path and the joint accelerations
of its joint path (what the tasks' reward terms and success criteria judge)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Smoothness"]


@dataclass(frozen=True)
class Smoothness:
    """Smoothness of a commanded motion, computed before simulation.

    Attributes:
        jerk_sq: squared jerk norm of the commanded sponge path per control step, [T] ((m/s³)²).
        jerk_ratio: its integral over that of the imitation in the same context (1 for action 0).
        joint_accel: peak commanded joint acceleration per control step, [T] (rad/s²).
    """

    jerk_sq: np.ndarray
    jerk_ratio: float
    joint_accel: np.ndarray

    def padded(self, count: int) -> Smoothness:
        """This smoothness of an episode's first steps, its per-step arrays padded with zeros to ``count`` steps
        (what the step twins charge for the episode so far)."""
        pad = count - len(self.jerk_sq)
        return Smoothness(np.pad(self.jerk_sq, (0, pad)), self.jerk_ratio, np.pad(self.joint_accel, (0, pad)))

    @staticmethod
    def jerk_squared(path: np.ndarray, dt: float) -> np.ndarray:
        """Squared jerk norm ``[T]`` of a path ``[T, d]`` sampled every ``dt`` (third differences, padded)."""
        if len(path) < 4:
            return np.zeros(len(path))
        jerk = np.diff(path, 3, axis=0) / dt**3
        sq = np.sum(jerk**2, axis=1)
        return np.r_[sq[:1], sq[:1], sq, sq[-1:]]

    @staticmethod
    def integrated_jerk(path: np.ndarray, dt: float) -> float:
        """Integrated squared jerk of a path ``[T, d]`` (sum over its steps of :meth:`jerk_squared`)."""
        return float(np.sum(Smoothness.jerk_squared(path, dt)))

    @staticmethod
    def speed_normalised(path: np.ndarray, dt: float) -> float:
        """Integrated squared jerk per integrated squared speed of a path ``[T, d]`` (1/s⁴).

        Scaling a path by any factor leaves it unchanged, and a slow travel of a fast pattern adds little
        to either integral, so a larger or travelling pattern that is as smooth scores as the imitation; a
        rough one (high-frequency content) scores its mean squared frequency⁴ higher."""
        speed = float(np.sum(np.diff(path, axis=0) ** 2)) / dt**2
        return Smoothness.integrated_jerk(path, dt) / max(speed, 1e-12)

    @staticmethod
    def peak_accel(q: np.ndarray, dt: float) -> np.ndarray:
        """Largest absolute joint acceleration ``[T]`` of a joint path ``[T, n]`` (second differences, padded)."""
        if len(q) < 3:
            return np.zeros(len(q))
        acc = np.max(np.abs(np.diff(q, 2, axis=0)), axis=1) / dt**2
        return np.r_[acc[:1], acc, acc[-1:]]
