"""Poses (position and orientation) for the rhythmic DMP: the orientation rides along as three more dimensions.

An orientation series ``q [L, 4]`` (unit quaternions, :mod:`rdmp_gym.dmp.quaternion`) becomes its tangent
coordinates about a reference orientation (the recording's mean): ``v = log(reference* q)``, three numbers (rad)
that move smoothly where the orientation does. A :class:`PoseDemonstration` holds the position and ``v`` side by
side, ``[L, p + 3]``, so one :class:`~rdmp_gym.dmp.rhythmic.RhythmicDMP` with one canonical system encodes the whole
pose: phase, tempo, transient, the anchor's sweep and the stop apply to the orientation as they do to the position. A
:class:`PoseDMP` maps its rollouts back, ``q = reference exp(v)``: unit quaternions by construction, continuous
(no sign flips). The reference is the recording's mean orientation, so the recording stays far from the tangent
map's singularity (a full turn from the reference; a half turn is passed smoothly).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, NamedTuple

import numpy as np
from scipy.interpolate import CubicSpline

from ..signals.demonstrations import Demonstration
from ..signals.filters import despike
from ..validation import as_finite_array, check_positive, check_time_grid
from . import quaternion
from .rhythmic import DMPStepper, GroupSelection, RhythmicDMP

__all__ = ["ORIENTATION_DIMS", "Pose", "PoseDMP", "PoseDemonstration", "PoseStepper", "select_dims"]

ORIENTATION_DIMS = 3        # tangent coordinates of an orientation


class Pose(NamedTuple):
    """Positions ``[..., p]`` and unit quaternions ``[..., 4]`` (w, x, y, z)."""

    position: np.ndarray
    orientation: np.ndarray


def _reference(reference: object) -> np.ndarray:
    """``reference [4]`` checked and normalised."""
    reference = quaternion.check_unit(reference, "reference")
    if reference.shape != (4,):
        raise ValueError(f"reference: expected one quaternion [4], got shape {reference.shape}")
    return reference


@dataclass(frozen=True, eq=False)
class PoseDemonstration:
    """A recorded pose: ``demo.Y [L, p + 3]`` holds the position (p columns) and the orientation's tangent
    coordinates (rad) about ``reference [4]``."""

    demo: Demonstration
    reference: np.ndarray

    def __post_init__(self) -> None:
        if not isinstance(self.demo, Demonstration):
            raise TypeError(f"demo: expected a Demonstration, got {type(self.demo).__name__}")
        if self.demo.n_dims <= ORIENTATION_DIMS:
            raise ValueError(f"demo: expected position columns and {ORIENTATION_DIMS} tangent columns, got "
                             f"{self.demo.n_dims} columns")
        object.__setattr__(self, "reference", _reference(self.reference))

    @property
    def n_position(self) -> int:
        """The number of position columns p."""
        return self.demo.n_dims - ORIENTATION_DIMS

    @property
    def position(self) -> Demonstration:
        """The position part ``[L, p]`` as a demonstration of its own."""
        return Demonstration(self.demo.t, self.demo.Y[:, : self.n_position], name=self.demo.name)

    @property
    def tangent(self) -> Demonstration:
        """The orientation's tangent coordinates ``[L, 3]`` (rad) as a demonstration of its own."""
        return Demonstration(self.demo.t, self.demo.Y[:, self.n_position:], name=self.demo.name)

    @property
    def orientations(self) -> np.ndarray:
        """The orientation ``[L, 4]`` (unit quaternions, continuous signs)."""
        return quaternion.from_tangent(self.demo.Y[:, self.n_position:], self.reference)

    @classmethod
    def from_samples(cls, t: np.ndarray, positions: np.ndarray, orientations: np.ndarray, rate: float = 100.0, *,
                     name: str = "", outliers: bool = True) -> PoseDemonstration:
        """Samples at uneven stamps ``t [L]`` (s) on an even grid at ``rate`` Hz: positions ``[L, p]`` (m) and
        unit quaternions ``[L, 4]`` (either sign per row); the tangent coordinates about their mean orientation
        are resampled like the positions (outliers removed first unless ``outliers=False``, then a cubic
        spline, :func:`rdmp_gym.signals.demonstrations.to_demonstration`)."""
        t = check_time_grid(t, "t", uniform=False, min_length=4)
        positions = as_finite_array(positions, "positions", ndim=(1, 2))
        positions = positions[:, None] if positions.ndim == 1 else positions
        q = quaternion.check_unit(orientations, "orientations")
        if positions.shape[0] != t.size or q.shape != (t.size, 4):
            raise ValueError(f"positions, orientations: expected {t.size} rows each (one per time stamp), got "
                             f"shapes {positions.shape} and {q.shape}")
        reference = quaternion.mean(q)
        samples = np.concatenate([positions, quaternion.to_tangent(q, reference)], axis=1)
        samples = despike(samples) if outliers else samples
        grid = t[0] + np.arange(int(np.floor((t[-1] - t[0]) * check_positive(rate, "rate") + 1e-9)) + 1) / rate
        return cls(Demonstration(grid, CubicSpline(t, samples, axis=0)(grid), name=name), reference)


def _pose(Y: np.ndarray, reference: np.ndarray) -> Pose:
    """Rollout samples ``[..., p + 3]`` as positions and unit quaternions."""
    return Pose(Y[..., :-ORIENTATION_DIMS], quaternion.from_tangent(Y[..., -ORIENTATION_DIMS:], reference))


class PoseDMP:
    """A :class:`~rdmp_gym.dmp.rhythmic.RhythmicDMP` ``dmp`` whose last three dimensions are tangent coordinates (rad)
    of the orientation about ``reference [4]``; rollouts come back as a :class:`Pose`.

    Parameters (``get_params``, learners' ``thetas``) are those of ``dmp``.
    """

    def __init__(self, dmp: RhythmicDMP, reference: np.ndarray) -> None:
        if not isinstance(dmp, RhythmicDMP):
            raise TypeError(f"dmp: expected a RhythmicDMP, got {type(dmp).__name__}")
        if dmp.n_dims <= ORIENTATION_DIMS:
            raise ValueError(f"dmp: expected position dimensions and {ORIENTATION_DIMS} tangent dimensions, got "
                             f"{dmp.n_dims}")
        self.dmp, self.reference = dmp, _reference(reference)

    @property
    def n_position(self) -> int:
        """The number of position dimensions p."""
        return self.dmp.n_dims - ORIENTATION_DIMS

    @property
    def position(self) -> RhythmicDMP:
        """The position part alone (a p-dimensional DMP with the same canonical system and weights)."""
        return select_dims(self.dmp, slice(0, self.n_position))

    @property
    def tangent(self) -> RhythmicDMP:
        """The orientation part alone: a 3-dimensional DMP of the tangent coordinates (rad)."""
        return select_dims(self.dmp, slice(self.n_position, None))

    def _start(self, position: object, orientation: object, transient: int) -> np.ndarray | None:
        """The start ``y0 [p + 3]`` for a start pose (either part ``None``: the demonstrated one)."""
        if position is None and orientation is None:
            return None
        start = self.dmp.transients[transient].start.copy()
        if position is not None:
            position = as_finite_array(position, "position", ndim=1)
            if position.size != self.n_position:
                raise ValueError(f"position: expected {self.n_position} values, got {position.size}")
            start[: self.n_position] = position
        if orientation is not None:
            relative = quaternion.multiply(quaternion.conjugate(self.reference),
                                           quaternion.check_unit(orientation, "orientation"))
            branches = quaternion.log_map(np.stack([relative, -relative]))      # q and -q: the nearer branch
            near = start[self.n_position:]
            start[self.n_position:] = branches[int(np.argmin(np.linalg.norm(branches - near, axis=1)))]
        return start

    def rollout(self, t: np.ndarray, transient: int = 0, position: np.ndarray | None = None,
                orientation: np.ndarray | None = None, *, tempo: float | None = None, start_blend: bool = True,
                stop_at: Any = None) -> Pose:
        """The pose ``([T, p], [T, 4])`` at even times ``t [T]`` from the start pose ``position [p]``,
        ``orientation [4]`` (default: the demonstrated one); other arguments as in :meth:`RhythmicDMP.rollout`."""
        y0 = self._start(position, orientation, self.dmp._check_transient(transient))
        Y = self.dmp.rollout(t, transient, y0, tempo=tempo, start_blend=start_blend, stop_at=stop_at)
        return _pose(Y, self.reference)

    def rollout_batch(self, thetas: np.ndarray, t: np.ndarray, groups: GroupSelection = None,
                      **keywords: Any) -> Pose:
        """B parameter vectors of ``dmp`` at once (:meth:`RhythmicDMP.rollout_batch`, same keywords):
        ``([B, T, p], [B, T, 4])``."""
        return _pose(self.dmp.rollout_batch(thetas, t, groups, **keywords), self.reference)

    def with_params(self, theta: np.ndarray, groups: GroupSelection = None) -> PoseDMP:
        """A copy whose selected parameter groups of ``dmp`` are ``theta [P]``."""
        return PoseDMP(self.dmp.with_params(theta, groups), self.reference)

    def start(self, dt: float, transient: int = 0, position: np.ndarray | None = None,
              orientation: np.ndarray | None = None, *, tempo: float | None = None,
              start_blend: bool = True) -> PoseStepper:
        """An online integrator of the pose, ``dt`` s per step (:meth:`RhythmicDMP.start`)."""
        y0 = self._start(position, orientation, self.dmp._check_transient(transient))
        return PoseStepper(self.dmp.start(dt, transient, y0, tempo=tempo, start_blend=start_blend), self.reference)

    def __repr__(self) -> str:
        return f"PoseDMP(n_position={self.n_position}, period={self.dmp.period:.4g}, reference={self.reference})"


class PoseStepper:
    """:class:`~rdmp_gym.dmp.rhythmic.DMPStepper` of a :class:`PoseDMP`: each step returns the pose."""

    def __init__(self, stepper: DMPStepper, reference: np.ndarray) -> None:
        self.stepper, self.reference = stepper, reference

    @property
    def pose(self) -> Pose:
        """The current ``(position [p], orientation [4])``."""
        return _pose(self.stepper.state[0], self.reference)

    def request_stop(self, exit_phase: float | None = None) -> float:
        """End the movement at the demonstrated rest (:meth:`DMPStepper.request_stop`); the exit time (s)."""
        return self.stepper.request_stop(exit_phase)

    def step(self, coupling: np.ndarray | None = None) -> Pose:
        """Advance by ``dt``; ``coupling [p + 3]`` as in :meth:`DMPStepper.step` (the last three on the
        tangent coordinates). Returns the new pose."""
        self.stepper.step(coupling)
        return self.pose


def select_dims(dmp: RhythmicDMP, dims: slice) -> RhythmicDMP:
    """The dimensions ``dims`` of ``dmp`` as a DMP of their own (dimensions do not interact: its rollouts are
    those columns of ``dmp``'s)."""
    ending = None if dmp.ending is None else replace(dmp.ending, goal=dmp.ending.goal[dims],
                                                     weights=dmp.ending.weights[dims])
    sweep = None if dmp.sweep is None else dmp.sweep.with_points(dmp.sweep.points[:, dims])
    transients = [replace(s, start=s.start[dims], start_velocity=s.start_velocity[dims]) for s in dmp.transients]
    return RhythmicDMP(dmp.canonical, dmp.basis, dmp.weights[dims], transients, dmp.anchor[dims], dmp.alpha_z,
                       dmp.amplitude[dims], ending, sweep)
