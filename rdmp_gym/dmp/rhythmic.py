"""The rhythmic DMP with transients (Ernesti et al. 2012): rollout, step, parameters.

The formulation (basis functions, fades, mixture) is in :mod:`rdmp_gym.dmp.basis`, the fit in
:mod:`rdmp_gym.dmp.fitting`.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, replace
from typing import Any, NamedTuple

import numpy as np

from ..signals.demonstrations import Demonstration
from ..validation import as_finite_array, check_positive, check_time_grid
from .basis import BasisSet, normalize
from .batched import batched_forcing
from .canonical import CanonicalSystem
from .cycles import (
    DEFAULT_HANDOVER,
    cycle_starts,
    handover_ramp,
    handover_ramp_rate,
    handover_width,
    next_cycle_start,
    rollout_cycles,
)
from .ending import Ending, StopPlan, StopRequest, plan_stop
from .fitting import PAPER_SETTINGS, fit_rhythmic
from .parameters import ParameterLayout, group_key
from .settings import DEFAULT_FIT, FitSettings
from .start import TransientStart, blend_shift, settled_state, start_blend_profiles
from .sweep import Sweep
from .transformation import cached_system

__all__ = ["PAPER_SETTINGS", "DMPStepper", "RhythmicDMP", "StopRequest", "TransientStart", "start_blend_profiles"]

logger = logging.getLogger(__name__)

#: the speed factors ``tempo`` a rollout accepts
TEMPO_RANGE = (1e-6, 1e6)

GroupSelection = str | Iterable[str] | None


class _Batch(NamedTuple):
    """B parameter sets of one DMP, decoded from ``thetas [B, P]`` (see :meth:`RhythmicDMP._decode`)."""

    weights: np.ndarray                     # [B, d, D]
    inits: np.ndarray                       # [B, K, 2] (after the choice of transient: [B, 2])
    anchors: np.ndarray                     # [B, d]
    amplitudes: np.ndarray                  # [B, d]
    sweeps: np.ndarray | None               # [B, V, d] via points of the anchor's travel, None without a sweep
    stop_weights: np.ndarray | None         # [B, d, S], None without an ending

    def rows(self, rows: np.ndarray) -> _Batch:
        """The parameter sets of ``rows``."""
        return _Batch(*(None if part is None else part[rows] for part in self))


class _StartState(NamedTuple):
    """Where B rollouts start: ``y0``, ``yd0`` ``[B, d]`` and, for the smooth start, each blend's length ``[B]`` (s;
    ``None``: the paper's start)."""

    y0: np.ndarray
    yd0: np.ndarray
    blend_length: np.ndarray | None

    def rows(self, rows: np.ndarray) -> _StartState:
        return _StartState(self.y0[rows], self.yd0[rows], None if self.blend_length is None
                           else self.blend_length[rows])


def travel_input(sweep: Sweep, tau: np.ndarray, points: np.ndarray | None, omega: float, alpha_z: float
                 ) -> np.ndarray:
    """The anchor term that carries the pattern rigidly along ``sweep``: ``[T, d]`` (``[B, T, d]`` for ``points
    [B, K, d]``) at unit-tempo times ``tau [T]``, ``g + g' / (beta_z Omega) + g'' / (alpha_z beta_z Omega^2)`` with
    g the sweep's offset and ``Omega`` the unit-tempo angular velocity. With it in place of the anchor, ``y - g(t)``
    obeys (4) exactly as without the sweep (the spring and damper act relative to the moving anchor), so the
    pattern travels with no lag; at any tempo, since g' and Omega scale alike."""
    beta_z = alpha_z / 4.0
    return (sweep.offsets(tau, points) + sweep.offsets(tau, points, 1) / (beta_z * omega)
            + sweep.offsets(tau, points, 2) / (alpha_z * beta_z * omega**2))


def _transform_matrix(n_dims: int, scale: float | np.ndarray, rotation: float | np.ndarray | None
                      ) -> np.ndarray | None:
    """``M = R diag(scale)``, ``[d, d]``; ``None`` for the identity."""
    scale = as_finite_array(scale, "scale", ndim=(0, 1))
    if scale.ndim == 1 and scale.size != n_dims:
        raise ValueError(f"scale: expected a number or {n_dims} numbers, got {scale.size}")
    if rotation is None:
        matrix = np.eye(n_dims)
    elif np.ndim(rotation) == 0:
        if n_dims < 2:
            raise ValueError("rotation: an angle needs at least 2 dimensions")
        angle = float(as_finite_array(rotation, "rotation", ndim=0))
        matrix = np.eye(n_dims)
        matrix[:2, :2] = [[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]]
    else:
        matrix = as_finite_array(rotation, "rotation", ndim=2)
        if matrix.shape != (n_dims, n_dims) or not np.allclose(matrix @ matrix.T, np.eye(n_dims), atol=1e-9):
            raise ValueError(f"rotation: expected an angle or an orthogonal {n_dims}x{n_dims} matrix")
    if rotation is None and np.all(scale == 1.0):
        return None
    return matrix * scale


class RhythmicDMP:
    """A rhythmic DMP that encodes a periodic pattern and K transients that lead into it.

    One canonical system (3) is shared by d transformation systems (4) (paper V-B). The forcing term
    (5) mixes N periodic and ``sum_k M_k`` transient basis functions (paper V-A).

    Args:
        canonical: the shared canonical system (its ``period`` sets Omega).
        basis: the basis functions.
        weights: ``[d, D]`` weights, periodic ones first, then each transient's.
        transients: one :class:`TransientStart` per encoded transient.
        anchor: ``[d]`` anchor g, the centre of the periodic pattern.
        alpha_z: damping gain of the transformation system (``beta_z = alpha_z / 4``; default the fit's,
            :data:`~rdmp_gym.dmp.settings.DEFAULT_FIT`).
        amplitude: ``[d]`` factors that scale the movement about the anchor (forcing term and default
            start); ones by default. A learnable parameter group, like the weights.
        ending: the encoded end of the movement (:mod:`rdmp_gym.dmp.stopping`), or ``None``.
        sweep: the anchor's travel (:class:`~rdmp_gym.dmp.sweep.Sweep`, offsets from ``anchor``), or ``None``: the
            anchor stays where it is.
    """

    def __init__(self, canonical: CanonicalSystem, basis: BasisSet, weights: np.ndarray,
                 transients: Sequence[TransientStart], anchor: np.ndarray, alpha_z: float = DEFAULT_FIT.alpha_z,
                 amplitude: np.ndarray | None = None, ending: Ending | None = None, sweep: Sweep | None = None
                 ) -> None:
        self.canonical = canonical
        self.basis = basis
        self.weights = np.ascontiguousarray(as_finite_array(weights, "weights", ndim=2))
        self.transients = tuple(transients)
        self.anchor = as_finite_array(anchor, "anchor", ndim=1)
        self.alpha_z = check_positive(alpha_z, "alpha_z")
        self.amplitude = (np.ones(self.anchor.size) if amplitude is None
                          else as_finite_array(amplitude, "amplitude", ndim=1))
        if self.amplitude.shape != self.anchor.shape:
            raise ValueError(f"amplitude: expected shape {self.anchor.shape}, got {self.amplitude.shape}")
        if self.weights.shape != (self.anchor.size, basis.n_basis):
            raise ValueError(f"weights: expected shape {(self.anchor.size, basis.n_basis)}, got {self.weights.shape}")
        if len(self.transients) != len(basis.transient_sizes):
            raise ValueError(f"transients: expected {len(basis.transient_sizes)}, got {len(self.transients)}")
        if ending is not None and (not isinstance(ending, Ending) or ending.goal.size != self.anchor.size):
            raise ValueError(f"ending: expected an Ending with a goal of {self.anchor.size} values")
        if sweep is not None and (not isinstance(sweep, Sweep) or sweep.n_dims != self.anchor.size):
            raise ValueError(f"sweep: expected a Sweep with via points of {self.anchor.size} values")
        self.ending = ending
        self.sweep = sweep
        self.layout = ParameterLayout(self.n_dims, basis.n_periodic, basis.transient_sizes,
                                      0 if ending is None else ending.weights.size,
                                      0 if sweep is None else sweep.points.size)

    # ------------------------------------------------------------------ properties
    @property
    def n_dims(self) -> int:
        return int(self.anchor.size)

    @property
    def period(self) -> float:
        return self.canonical.period

    @property
    def n_transients(self) -> int:
        return len(self.transients)

    @property
    def starts(self) -> np.ndarray:
        """``[K, d]`` start position of each transient's demonstration."""
        return np.stack([transient.start for transient in self.transients])

    # ------------------------------------------------------------------ fitting
    @classmethod
    def fit(cls, demos: Demonstration | Sequence[Demonstration], n_periodic: int | None = None,
            n_transient: int | Sequence[int] | None = None, method: str | None = None, *,
            settings: FitSettings | None = None, **keywords: Any) -> RhythmicDMP:
        """Fit a DMP to one or more demonstrations that share a periodic pattern (paper III-E, V-A).

        The fit is :func:`rdmp_gym.dmp.fitting.fit_rhythmic`: ``settings`` (a
        :class:`~rdmp_gym.dmp.settings.FitSettings`, default :data:`~rdmp_gym.dmp.settings.DEFAULT_FIT`: N = 40, M = 44,
        ``"trajectory"``) with ``n_periodic``, ``n_transient``, ``method`` and any setting by name over it; ``keywords``
        also take ``segmentations`` and ``period``.
        """
        return cls(*fit_rhythmic(demos, n_periodic, n_transient, method, settings=settings, **keywords))

    # ------------------------------------------------------------------ rollouts
    def _check_transient(self, transient: int) -> int:
        if not isinstance(transient, (int, np.integer)) or not 0 <= transient < self.n_transients:
            raise ValueError(f"transient: expected an index in [0, {self.n_transients}), got {transient!r}")
        return int(transient)

    def _tempo(self, tempo: float | None) -> float:
        """The requested tempo, or the canonical system's when ``None`` (a speed factor within
        ``TEMPO_RANGE``: beyond it the timescales over- or underflow float64)."""
        if tempo is None:
            return self.canonical.tempo
        tempo = check_positive(tempo, "tempo")
        if not TEMPO_RANGE[0] <= tempo <= TEMPO_RANGE[1]:
            low, high = TEMPO_RANGE
            raise ValueError(f"tempo: expected a speed factor in [{low:g}, {high:g}], got {tempo!r}")
        return tempo

    def _vector(self, value: object, default: np.ndarray, name: str, batch: int) -> np.ndarray:
        """``value`` (``[d]`` or ``[B, d]``, or None for ``default``) broadcast to ``[B, d]``."""
        array = default if value is None else as_finite_array(value, name, ndim=(1, 2))
        if array.shape[-1] != self.n_dims or (array.ndim == 2 and array.shape[0] != batch):
            raise ValueError(f"{name}: expected shape ({self.n_dims},) or ({batch}, {self.n_dims}), got {array.shape}")
        return np.broadcast_to(array, (batch, self.n_dims))

    def _forcing(self, canonical: CanonicalSystem, times: np.ndarray, weights: np.ndarray, inits: np.ndarray,
                 amplitudes: np.ndarray, transform: np.ndarray | None) -> np.ndarray:
        """Forcing term ``[B, T, d]`` at ``times [T]`` along the paths from ``inits [B, 2]``, times
        ``M diag(amplitude)``; the basis is evaluated once per distinct initial condition."""
        unique, inverse = (inits, np.zeros(1, dtype=int)) if len(inits) == 1 else np.unique(inits, axis=0,
                                                                                             return_inverse=True)
        if unique.shape[0] == 1:              # one canonical path shared by the batch
            phis, radii = canonical.state(times, unique[:, 0], unique[:, 1])          # [1, T] each
            forcing = self.basis.forcing(phis[0], radii[0], weights)
        else:                                 # every rollout on its own path (perturbed initial conditions)
            if unique.shape[0] < inits.shape[0]:
                phis, radii = canonical.state(times, unique[:, 0], unique[:, 1])      # [U, T] each
                phis, radii = phis[inverse.ravel()], radii[inverse.ravel()]
            else:                             # all distinct: the paths in the rows' order, with no copy
                phis, radii = canonical.state(times, inits[:, 0], inits[:, 1])        # [B, T] each
            forcing = batched_forcing(self.basis, phis, radii, weights)
        forcing *= amplitudes[:, None, :]
        return forcing if transform is None else forcing @ transform.T

    def _stop_forcing(self, canonical: CanonicalSystem, times: np.ndarray, weights: np.ndarray, inits: np.ndarray,
                      amplitudes: np.ndarray, transform: np.ndarray | None, stop: StopPlan,
                      stop_weights: np.ndarray) -> np.ndarray:
        """Forcing term ``[B, T, d]`` like :meth:`_forcing`, with the stop family after ``stop.exit_time``
        (``stop_weights [B, d, S]``); one mixture per distinct initial condition."""
        unique, inverse = np.unique(inits, axis=0, return_inverse=True)
        phis, radii = canonical.state(times, unique[:, 0], unique[:, 1])              # [U, T] each
        tau = (times - stop.exit_time) * canonical.tempo
        forcing = np.empty((weights.shape[0], times.size, self.n_dims))
        for index, (phi, r) in enumerate(zip(phis, radii, strict=True)):
            members = np.flatnonzero(inverse.ravel() == index)
            forcing[members] = self.ending.forcing(self.basis, phi, r, tau, stop.rotation, weights[members],
                                                   stop_weights[members])
        forcing *= amplitudes[:, None, :]
        return forcing if transform is None else forcing @ transform.T

    def _settled(self, canonical: CanonicalSystem, weights: np.ndarray, inits: np.ndarray, anchors: np.ndarray,
                 amplitudes: np.ndarray, transform: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
        """``(y, yd)`` ``[B, d]`` that the forcing term leads to at t = 0 (see :func:`settled_state`)."""
        forcing = self._forcing(canonical, np.zeros(1), weights, inits, amplitudes, transform)[:, 0]
        return settled_state(forcing, anchors, self.alpha_z)

    def settled_start(self, transient: int = 0, tempo: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The state ``(y [d], yd [d])`` that transient ``transient``'s forcing term leads to at its start
        (:func:`settled_state`; for a demonstration that starts at rest, about its start). From there the
        acceleration starts at 0 and follows the forcing term with no fast transient of its own; the smooth
        start (``start_blend=True``) blends from the requested start into the motion from this state.
        """
        k = self._check_transient(transient)
        canonical = replace(self.canonical, tempo=self._tempo(tempo))
        start = self.transients[k]
        y, yd = self._settled(canonical, self.weights[None], np.array([[start.phi0, start.r0]]), self.anchor[None],
                              self.amplitude[None], None)
        return y[0], yd[0]

    def _simulate(self, t: np.ndarray, batch: _Batch, start: _StartState, tempo: float,
                  transform: np.ndarray | None, stop: StopPlan | None = None, velocity: bool = True
                  ) -> tuple[np.ndarray, np.ndarray | None]:
        """Open-loop integration of B parameter sets ``batch`` (inits ``[B, 2]``) from ``start`` -> positions and
        velocities ``[B, T, d]`` (``None`` for the velocities unless ``velocity``). The forcing term is multiplied by
        ``M diag(amplitude)``. With ``start.blend_length [B]`` (s) the start is blended (``start_blend``): the result
        is the settled motion plus a quintic offset ``e(t)`` that starts at ``(y0, yd0)`` minus the settled state and
        is 0 from ``blend_length`` on. A ``stop`` (with ``batch.stop_weights [B, d, S]``) ends the movement at
        ``stop.goal [B, d]``. ``batch.sweeps [B, K, d]``: via points of the anchor's travel along ``self.sweep``'s
        timing."""
        weights, inits, anchors, amplitudes, sweeps, stop_weights = batch
        y0, yd0, blend_length = start
        t = check_time_grid(t, "t")
        elapsed = t - t[0]
        dt = float(elapsed[-1] / (elapsed.size - 1))
        canonical = replace(self.canonical, tempo=tempo)
        if stop is None:
            forcing = self._forcing(canonical, elapsed, weights, inits, amplitudes, transform)
        else:
            forcing = self._stop_forcing(canonical, elapsed, weights, inits, amplitudes, transform, stop,
                                         stop_weights)
        omega = canonical.omega * tempo
        path = anchors
        if blend_length is not None:
            y_settled, yd_settled = self._settled(canonical, weights, inits, anchors, amplitudes, transform)
            path = blend_shift(elapsed, blend_length, y0 - y_settled, yd0 - yd_settled, omega, self.alpha_z)
            path += anchors[:, None, :]
        travel = 0.0 if sweeps is None else travel_input(self.sweep, elapsed * tempo, sweeps, self.canonical.omega,
                                                         self.alpha_z)                            # [B, T, d]
        if sweeps is not None:
            path = path + travel if path.ndim == 3 else travel + anchors[:, None, :]
        if stop is not None:        # the anchor blends to the goal (after the start blend has ended)
            blend = self.ending.anchor_blend((elapsed - stop.exit_time) * tempo)[None, :, None]
            path = (path if path.ndim == 3 else path[:, None, :]) + blend * (
                (stop.goal - anchors)[:, None, :] - travel)
        system = cached_system(omega, dt, self.alpha_z)
        with np.errstate(all="ignore"):
            u = system.input(path, forcing, out=forcing, scratch=path is not anchors)   # a blended path is ours
            del path, forcing
            y, z = system.rollout(u, y0, yd0 / omega, velocity)
            if velocity:
                z *= omega
        if not (np.all(np.isfinite(y)) and (z is None or np.all(np.isfinite(z)))):
            raise ValueError("rollout: the result overflowed to NaN or inf; the period, gains, weights or time grid "
                             f"are out of range (period {self.period:g} s, alpha_z {self.alpha_z:g}, tempo {tempo:g})")
        return y, z

    def _start(self, k: np.ndarray, y0: object, yd0: object, tempo: float, anchors: np.ndarray,
               amplitudes: np.ndarray, transform: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Initial ``(y0, yd0)`` ``[B, d]`` for transients ``k [B]``, anchors and amplitudes ``[B, d]``.

        The defaults are the demonstration's start and start velocity, transformed like the whole movement
        (``g + M diag(amplitude) (start - g)``, g the fitted anchor)."""
        starts = np.stack([self.transients[int(i)].start for i in k])
        velocities = np.stack([self.transients[int(i)].start_velocity for i in k])
        relative_start = amplitudes * (starts - self.anchor)                              # [B, d]
        default_yd0 = amplitudes * velocities * tempo / self.canonical.tempo
        if transform is not None:   # the whole demonstrated movement is transformed about the fitted anchor
            relative_start, default_yd0 = relative_start @ transform.T, default_yd0 @ transform.T
        y0 = self._vector(y0, self.anchor + relative_start, "y0", anchors.shape[0])
        return y0, self._vector(yd0, default_yd0, "yd0", anchors.shape[0])

    def _transients(self, transient: int | str, y0: object, batch: int, amplitudes: np.ndarray,
                    transform: np.ndarray | None = None) -> np.ndarray:
        """Transient index per row, ``[B]``: the given one, or under ``"nearest"`` the one whose (transformed)
        demonstrated start is nearest to ``y0`` (the first transient when ``y0`` is omitted)."""
        if not (isinstance(transient, str) and transient == "nearest"):
            return np.full(batch, self._check_transient(transient))
        if y0 is None:
            return np.zeros(batch, dtype=int)
        y0 = self._vector(y0, self.anchor, "y0", batch)
        relative = amplitudes[:, None, :] * (self.starts - self.anchor)[None]               # [B, K, d]
        if transform is not None:
            relative = relative @ transform.T
        return np.argmin(np.linalg.norm(self.anchor + relative - y0[:, None, :], axis=-1), axis=1)

    def _blend_lengths(self, k: np.ndarray, tempo: float, start_blend: bool) -> np.ndarray | None:
        return np.array([self.transients[int(i)].length / tempo for i in k]) if start_blend else None

    def rollout(self, t: np.ndarray, transient: int | str = 0, y0: np.ndarray | None = None,
                yd0: np.ndarray | None = None, anchor: np.ndarray | None = None, *,
                scale: float | np.ndarray = 1.0, rotation: float | np.ndarray | None = None,
                tempo: float | None = None, start_blend: bool = True, return_velocity: bool = False,
                stop_at: float | StopRequest | None = None) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
        """Reproduce the movement: transient ``transient`` from its own initial condition, then the cycle.

        Args:
            t: ``[T]`` evenly spaced times; ``t[0]`` is the start of the movement.
            transient: index of the encoded transient (its canonical initial condition), or ``"nearest"``:
                the one whose demonstrated start is nearest to ``y0`` (paper V-A).
            y0, yd0: ``[d]`` start position/velocity (default: that transient's demonstration start).
            anchor: ``[d]`` new anchor g (default: the fitted one). The periodic part moves with it.
            scale: amplitude factor (a number or ``[d]``) of the movement about the anchor.
            rotation: an angle (rad, about the axis normal to dims 0 and 1) or an orthogonal ``[d, d]`` matrix.
                With ``scale``/``rotation`` the whole movement is transformed, ``y - g -> M (y - g)`` with
                ``M = R diag(scale)``: the default start becomes ``g + M (start - g)`` (g: the fitted anchor);
                the result is exact, and exact on the periodic part for any explicit ``y0``.
            tempo: speed factor (default: the canonical system's; 0.5 = half speed).
            start_blend: the smooth start (default): the motion the forcing term leads to (see
                :meth:`settled_start`) plus an offset that starts at ``(y0, yd0)`` minus that state and fades
                out over the transient's length (quintic, C2): no spike from any start state or canonical
                initial condition, the demonstrated transient's shape from a shifted start. ``False``: the
                paper's behaviour, the spring closes any gap within about ``8 / (alpha_z Omega)`` seconds.
                The periodic part is the same either way.
            return_velocity: also return velocities.
            stop_at: end the movement: a stop requested at this time (s after ``t[0]``) leaves the cycle at the
                next demonstrated exit phase and comes to rest at the demonstrated goal, moved and transformed with
                the anchor like the periodic part (needs a DMP fitted with :func:`rdmp_gym.dmp.stopping.fit_ending`); a
                :class:`StopRequest` ``(at, exit_phase, goal)`` gives the exit phase (rad) and the goal ``[d]`` too.
                A request during the start transient is served once the transient has reached the cycle.
        Returns:
            positions ``[T, d]`` (and velocities ``[T, d]``).
        """
        tempo = self._tempo(tempo)
        transform = _transform_matrix(self.n_dims, scale, rotation)
        anchors = self._vector(anchor, self.anchor, "anchor", 1)
        amplitudes = self.amplitude[None]
        k = self._transients(transient, y0, 1, amplitudes, transform)
        y0, yd0 = self._start(k, y0, yd0, tempo, anchors, amplitudes, transform)
        start = self.transients[int(k[0])]
        inits = np.array([[start.phi0, start.r0]])
        stop = self._stop_plan(StopRequest.of(stop_at), start, tempo, anchors, amplitudes, transform)
        batch = _Batch(self.weights[None], inits, anchors, amplitudes,
                       None if self.sweep is None else self.sweep.points[None],
                       None if stop is None else self.ending.weights[None])
        y, yd = self._simulate(t, batch, _StartState(y0, yd0, self._blend_lengths(k, tempo, start_blend)), tempo,
                               transform, stop, return_velocity)
        return (y[0], yd[0]) if return_velocity else y[0]

    def _stop_plan(self, request: StopRequest | None, start: TransientStart, tempo: float, anchors: np.ndarray,
                   amplitudes: np.ndarray, transform: np.ndarray | None = None) -> StopPlan | None:
        """The stop ``request`` (``None``: no stop); default goals ``[B, d]`` move with the anchors.
        A request during the start transient of ``start`` is served once the transient has reached the cycle."""
        if request is None:
            return None
        if self.ending is None:
            raise ValueError("stop_at: this DMP encodes no end of the movement; fit it with "
                             "rdmp_gym.dmp.stopping.fit_ending")
        relative = amplitudes * (self.ending.goal - self.anchor)
        if transform is not None:
            relative = relative @ transform.T
        goals = self._vector(request.goal, anchors + relative, "goal", anchors.shape[0])
        stop_at = float(as_finite_array(request.at, "stop_at", ndim=0))
        if stop_at < 0.0:
            raise ValueError(f"stop_at: expected a time >= 0, got {stop_at!r}")
        return plan_stop(self.ending, max(stop_at, start.length / tempo), start.phi0, self.canonical.omega * tempo,
                         goals, request.exit_phase)

    def with_ending(self, ending: Ending | None) -> RhythmicDMP:
        """A copy of this DMP with another end of the movement (``None`` removes it)."""
        return RhythmicDMP(self.canonical, self.basis, self.weights, self.transients, self.anchor, self.alpha_z,
                           self.amplitude, ending, self.sweep)

    def with_weights(self, weights: np.ndarray) -> RhythmicDMP:
        """A copy of this DMP with the forcing weights ``weights [d, D]`` (periodic first, then each transient's)."""
        return RhythmicDMP(self.canonical, self.basis, weights, self.transients, self.anchor, self.alpha_z,
                           self.amplitude, self.ending, self.sweep)

    def with_sweep(self, sweep: Sweep | None) -> RhythmicDMP:
        """A copy of this DMP whose anchor travels along ``sweep`` (``None``: the anchor stays in place)."""
        return RhythmicDMP(self.canonical, self.basis, self.weights, self.transients, self.anchor, self.alpha_z,
                           self.amplitude, self.ending, sweep)

    def rollout_batch(self, thetas: np.ndarray, t: np.ndarray, groups: GroupSelection = None,
                      transient: int | str = 0, y0: np.ndarray | None = None, yd0: np.ndarray | None = None,
                      anchor: np.ndarray | None = None, tempo: float | None = None,
                      start_blend: bool = True, stop_at: float | StopRequest | None = None) -> np.ndarray:
        """Roll out B parameter vectors at once (the selected ``groups`` of each; the rest as fitted).

        Args:
            thetas: ``[B, P]`` parameter vectors, P = ``self.layout.size(groups)``.
            t: ``[T]`` evenly spaced times.
            groups: which parameter groups ``thetas`` holds (see :mod:`rdmp_gym.dmp.parameters`).
            transient, y0, yd0, anchor, tempo, start_blend, stop_at: as in :meth:`rollout`;
                y0/yd0/anchor and the stop's goal may be ``[B, d]`` (under ``transient="nearest"`` each row picks its
                own transient). The stop is requested at the same time for all B; each row exits at the exit phase
                that follows its transient's fitted phase (their phases differ only where ``initial`` is selected).
        Returns:
            ``[B, T, d]`` positions.
        """
        thetas = as_finite_array(thetas, "thetas", ndim=2)
        if thetas.shape[0] == 0:
            raise ValueError("thetas: expected at least one parameter vector (B >= 1), got shape "
                             f"{thetas.shape}")
        decoded = self._decode(thetas, groups)
        batch = thetas.shape[0]
        anchors, amplitudes = decoded.anchors, decoded.amplitudes
        if anchor is not None:
            if "anchor" in self.layout.resolve(groups):
                raise ValueError("anchor: given both as an argument and in thetas (group 'anchor')")
            anchors = self._vector(anchor, self.anchor, "anchor", batch)
        tempo = self._tempo(tempo)
        k = self._transients(transient, y0, batch, amplitudes)
        y0, yd0 = self._start(k, y0, yd0, tempo, anchors, amplitudes)
        decoded = decoded._replace(inits=decoded.inits[np.arange(batch), k], anchors=anchors)
        starts = _StartState(y0, yd0, self._blend_lengths(k, tempo, start_blend))
        request = StopRequest.of(stop_at)
        if request is None:
            return self._simulate(t, decoded, starts, tempo, None, velocity=False)[0]
        goals = None if request.goal is None else self._vector(request.goal, self.anchor, "goal", batch)
        result = np.empty((batch, check_time_grid(t, "t").size, self.n_dims))
        for index in np.unique(k):      # the exit time follows each transient's own phase
            rows = np.flatnonzero(k == index)
            stop = self._stop_plan(request if goals is None else replace(request, goal=goals[rows]),
                                   self.transients[index], tempo, anchors[rows], amplitudes[rows])
            result[rows] = self._simulate(t, decoded.rows(rows), starts.rows(rows), tempo, None, stop,
                                          velocity=False)[0]
        return result

    def rollout_cycles(self, thetas: np.ndarray, t: np.ndarray, starts: np.ndarray | None = None,
                       handover: float = DEFAULT_HANDOVER, **rollout: Any) -> np.ndarray:
        """The path ``[T, d]`` of parameters that change from cycle to cycle: row ``k`` of ``thetas [K, P]`` from the
        start of cycle ``k`` on (``starts [K]``, s; default: :func:`~rdmp_gym.dmp.cycles.cycle_starts` of ``t``'s
        span), handed over within ``handover`` periods (:func:`~rdmp_gym.dmp.cycles.rollout_cycles`); ``rollout``:
        the keywords of :meth:`rollout_batch`."""
        t = np.asarray(t, dtype=np.float64)
        if starts is None:
            transient = rollout.get("transient", 0)
            span = float(t[-1] - t[0]) + 1e-9
            starts = cycle_starts(self, span, transient if isinstance(transient, int) else 0,
                                  rollout.get("tempo"))[: len(thetas)]
        return rollout_cycles(self, thetas, t, starts, handover, **rollout)

    def start(self, dt: float, transient: int | str = 0, y0: np.ndarray | None = None,
              yd0: np.ndarray | None = None, anchor: np.ndarray | None = None,
              tempo: float | None = None, start_blend: bool = True) -> DMPStepper:
        """An online integrator that advances by ``dt`` per :meth:`DMPStepper.step` (for feedback);
        arguments as in :meth:`rollout`."""
        tempo = self._tempo(tempo)
        anchors = self._vector(anchor, self.anchor, "anchor", 1)
        amplitudes = self.amplitude[None]
        k = self._transients(transient, y0, 1, amplitudes)
        y0, yd0 = self._start(k, y0, yd0, tempo, anchors, amplitudes)
        offsets = self._blend_offsets(int(k[0]), y0[0], yd0[0], tempo, anchors[0]) if start_blend else None
        return DMPStepper(self, check_positive(dt, "dt"), int(k[0]), y0[0].copy(), yd0[0].copy(), anchors[0].copy(),
                          tempo, offsets)

    def _blend_offsets(self, transient: int, y0: np.ndarray, yd0: np.ndarray, tempo: float, anchor: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray]:
        """The smooth start's offsets ``(y0 - y_settled, yd0 - yd_settled)`` ``[d]`` of a stepper that starts
        transient ``transient`` at ``(y0, yd0)`` ``[d]`` about ``anchor [d]`` (see :meth:`settled_start`)."""
        start = self.transients[transient]
        y_settled, yd_settled = self._settled(replace(self.canonical, tempo=tempo), self.weights[None],
                                              np.array([[start.phi0, start.r0]]), anchor[None],
                                              self.amplitude[None], None)
        return y0 - y_settled[0], yd0 - yd_settled[0]

    def forcing(self, t: np.ndarray, transient: int = 0) -> np.ndarray:
        """The forcing term f along transient ``transient``'s canonical path, ``[T, d]`` (t from the start)."""
        start = self.transients[self._check_transient(transient)]
        phi, r = self.canonical.state(as_finite_array(t, "t", ndim=1), start.phi0, start.r0)
        return self.amplitude * self.basis.forcing(phi, r, self.weights)

    # ------------------------------------------------------------------ parameters
    def param_slices(self, groups: GroupSelection = None) -> dict[str, slice]:
        """Group name -> slice into the vector of the selected groups."""
        return self.layout.slices(groups)

    def get_params(self, groups: GroupSelection = None) -> np.ndarray:
        """The selected groups as one flat vector ``[P]`` (order: see :mod:`rdmp_gym.dmp.parameters`)."""
        parts = []
        for key in self.layout.keys(groups):
            if key.kind == "periodic":
                parts.append(self.weights[:, : self.basis.n_periodic].ravel())
            elif key.kind == "transient":
                parts.append(self.weights[:, self._transient_columns(key.transient)].ravel())
            elif key.kind == "initial":
                start = self.transients[key.transient]
                parts.append(np.array([start.phi0, start.r0]))
            elif key.kind == "anchor":
                parts.append(self.anchor.copy())
            elif key.kind == "stop":
                parts.append(self.ending.weights.ravel())
            elif key.kind == "sweep":
                parts.append(self.sweep.points.ravel())
            else:
                parts.append(self.amplitude.copy())
        return np.concatenate(parts)

    def _transient_columns(self, k: int) -> slice:
        offset = self.basis.n_periodic + sum(self.basis.transient_sizes[:k])
        return slice(offset, offset + self.basis.transient_sizes[k])

    def _decode(self, thetas: np.ndarray, groups: GroupSelection) -> _Batch:
        """``thetas [B, P]`` -> weights ``[B, d, D]``, initial conditions ``[B, K, 2]``, anchors and
        amplitudes ``[B, d]``, the sweep's via points ``[B, V, d]`` (``None`` without a sweep), stop weights
        ``[B, d, S]`` (``None`` without an ending)."""
        slices = self.layout.slices(groups)
        expected = self.layout.size(groups)
        if thetas.shape[-1] != expected:
            raise ValueError(f"theta: expected {expected} parameters for groups {list(slices)}, "
                             f"got {thetas.shape[-1]}")
        batch = thetas.shape[0]
        weights = np.repeat(self.weights[None], batch, axis=0)
        inits = np.repeat(np.array([[[s.phi0, s.r0] for s in self.transients]]), batch, axis=0)
        anchors = np.repeat(self.anchor[None], batch, axis=0)
        amplitudes = np.repeat(self.amplitude[None], batch, axis=0)
        stop_weights = None if self.ending is None else np.repeat(self.ending.weights[None], batch, axis=0)
        sweeps = None if self.sweep is None else np.repeat(self.sweep.points[None], batch, axis=0)
        for name, part in slices.items():
            values, key = thetas[:, part], group_key(name)
            if key.kind == "periodic":
                weights[:, :, : self.basis.n_periodic] = values.reshape(batch, self.n_dims, -1)
            elif key.kind == "transient":
                weights[:, :, self._transient_columns(key.transient)] = values.reshape(batch, self.n_dims, -1)
            elif key.kind == "initial":
                if np.any(values[:, 1] <= 0.0):
                    raise ValueError(f"theta: the initial radius r0 of {name} must be > 0")
                inits[:, key.transient] = values
            elif key.kind == "anchor":
                anchors = values.copy()
            elif key.kind == "stop":
                stop_weights = values.reshape(batch, self.n_dims, -1)
            elif key.kind == "sweep":
                sweeps = values.reshape(batch, -1, self.n_dims)
            else:
                amplitudes = values.copy()
        return _Batch(weights, inits, anchors, amplitudes, sweeps, stop_weights)

    def with_params(self, theta: np.ndarray, groups: GroupSelection = None) -> RhythmicDMP:
        """A new DMP whose selected groups are replaced by ``theta [P]``."""
        theta = as_finite_array(theta, "theta", ndim=1)
        weights, inits, anchors, amplitudes, sweeps, stop_weights = self._decode(theta[None], groups)
        transients = [replace(start, phi0=float(phi0), r0=float(r0))
                      for start, (phi0, r0) in zip(self.transients, inits[0], strict=True)]
        ending = None if self.ending is None else self.ending.with_weights(stop_weights[0])
        sweep = None if self.sweep is None else self.sweep.with_points(sweeps[0])
        return RhythmicDMP(self.canonical, self.basis, weights[0], transients, anchors[0], self.alpha_z,
                           amplitudes[0], ending, sweep)

    def param_time_weights(self, t: np.ndarray, groups: GroupSelection = None, transient: int = 0,
                           stop_at: float | None = None) -> np.ndarray:
        """How active each parameter is at each time, ``[T, P]`` in [0, 1] (PI²'s time weighting).

        A weight's entry is its basis function's normalised activation along the path of transient
        ``transient`` (with the stop requested at ``stop_at``, if given); the initial condition of that transient,
        the anchor, the amplitude and the sweep act throughout (1); another transient's initial condition does not
        act (0), nor do the stop weights without a stop.
        """
        k = self._check_transient(transient)
        start = self.transients[k]
        elapsed = as_finite_array(t, "t", ndim=1) - np.min(t)
        phi, r = self.canonical.state(elapsed, start.phi0, start.r0)
        stop = self._stop_plan(StopRequest.of(stop_at), start, self.canonical.tempo, self.anchor[None],
                               self.amplitude[None])
        if stop is None:
            activation = self.basis.normalized(phi, r)                               # [T, D]
        else:
            activation = normalize(self.ending.mixture(self.basis, phi, r, (elapsed - stop.exit_time)
                                                       * self.canonical.tempo, stop.rotation),
                                   self.basis.fading.floor)                                      # [T, D + S]
        columns = []
        for key in self.layout.keys(groups):
            if key.kind == "periodic":
                block = activation[:, : self.basis.n_periodic]
            elif key.kind == "transient":
                block = activation[:, self._transient_columns(key.transient)]
            elif key.kind == "stop" and stop is not None:
                block = activation[:, self.basis.n_basis:]
            else:
                acts = key.kind != "stop" and (key.kind != "initial" or key.transient == k)
                columns.append(np.full((phi.size, self.layout.sizes[str(key)]), float(acts)))
                continue
            columns.append(np.tile(block, (1, self.n_dims)))
        return np.concatenate(columns, axis=1)

    # ------------------------------------------------------------------ persistence
    def __repr__(self) -> str:
        return (f"RhythmicDMP(n_dims={self.n_dims}, period={self.period:.4g}, n_periodic={self.basis.n_periodic}, "
                f"transient_sizes={self.basis.transient_sizes})")


class _Blocks:
    """An input ``[d]`` per sample ``step`` (at ``step * dt``), computed ahead in blocks of ``size`` samples by
    ``compute(times [size]) -> [size, d]``."""

    def __init__(self, compute: Callable[[np.ndarray], np.ndarray], dt: float, size: int) -> None:
        self.compute, self.dt, self.size = compute, dt, size
        self.index, self.block = -1, np.empty(0)

    def __call__(self, step: int) -> np.ndarray:
        index, offset = divmod(step, self.size)
        if index != self.index:
            self.block = self.compute((index * self.size + np.arange(self.size)) * self.dt)
            self.index = index
        return self.block[offset]

    def reset(self) -> None:
        """Compute the block again at the next sample (the input has changed)."""
        self.index = -1


@dataclass
class _Change:
    """A change of a stepper's weights: the new parameters (``dmp`` and its start ``offsets``), the hand-over window
    from ``start`` for ``width`` s, the difference of the two inputs (``drive``) and the response to it from rest
    at the movement's start, ``y``, ``z`` ``[d]``."""

    dmp: RhythmicDMP
    offsets: tuple[np.ndarray, np.ndarray] | None
    start: float
    width: float
    drive: _Blocks
    y: np.ndarray
    z: np.ndarray


class DMPStepper:
    """Online integration of a :class:`RhythmicDMP`, one sample at a time, with an optional coupling term.

    Uses the same exact first-order-hold step as :meth:`RhythmicDMP.rollout`, so with no coupling
    both produce the same trajectory. A coupling term ``c [d]`` is added to the forcing term inside
    (4) and held over the step: ``dz/dt = Omega (alpha_z (beta_z (g - y) - z) + f + c)``. The
    canonical system does not depend on ``y``, so the open-loop part of the input (anchor, moved by the
    smooth start's offset, and forcing term) is computed ahead in blocks of ``BLOCK`` samples; a step then
    costs one 2x2 update. :meth:`change_weights` hands the movement over to other forcing weights at a cycle
    start, as :func:`~rdmp_gym.dmp.cycles.rollout_cycles` does.
    """

    BLOCK = 256

    def __init__(self, dmp: RhythmicDMP, dt: float, transient: int, y0: np.ndarray, yd0: np.ndarray,
                 anchor: np.ndarray, tempo: float, start_offsets: tuple[np.ndarray, np.ndarray] | None = None) -> None:
        self.dmp, self.dt, self.transient, self.anchor = dmp, dt, transient, anchor
        self.start_offsets = start_offsets
        self.blend_length = dmp.transients[transient].length / tempo
        self.canonical = replace(dmp.canonical, tempo=tempo)
        self.omega = self.canonical.omega * tempo
        self.system = cached_system(self.omega, dt, dmp.alpha_z)
        self.steps = 0
        self._start = (y0.copy(), yd0.copy())
        self._y, self._z = y0, yd0 / self.omega
        self._drive = _Blocks(lambda times: self._open_loop(times, self.dmp.weights, self.start_offsets), dt,
                              self.BLOCK)
        self._change: _Change | None = None
        self.stop: StopPlan | None = None

    @property
    def time(self) -> float:
        """Time since the start (s)."""
        return self.steps * self.dt

    def _open_loop(self, times: np.ndarray, weights: np.ndarray, offsets: tuple[np.ndarray, np.ndarray] | None
                   ) -> np.ndarray:
        """Open-loop part of the input at ``times [T]`` (s), ``alpha_z beta_z g(t) + f(t)`` ``[T, d]``, of the
        forcing weights ``weights [d, D]`` and the smooth start's ``offsets`` (``None``: the paper's start)."""
        start = self.dmp.transients[self.transient]
        phi, r = self.canonical.state(times, start.phi0, start.r0)
        travel = 0.0 if self.dmp.sweep is None else travel_input(
            self.dmp.sweep, times * self.canonical.tempo, None, self.dmp.canonical.omega, self.dmp.alpha_z)
        anchor = self.anchor + travel
        if offsets is not None:
            anchor = anchor + blend_shift(times, np.array([self.blend_length]), offsets[0][None], offsets[1][None],
                                          self.omega, self.dmp.alpha_z)[0]
        if self.stop is None:
            forcing = self.dmp.basis.forcing(phi, r, weights)
        else:
            tau = (times - self.stop.exit_time) * self.canonical.tempo
            forcing = self.dmp.ending.forcing(self.dmp.basis, phi, r, tau, self.stop.rotation, weights,
                                              self.dmp.ending.weights)
            away = self.stop.goal[0] - self.anchor - travel
            anchor = anchor + self.dmp.ending.anchor_blend(tau)[:, None] * away
        return self.dmp.alpha_z * self.system.beta_z * anchor + self.dmp.amplitude * forcing

    @property
    def state(self) -> tuple[np.ndarray, np.ndarray]:
        """Current ``(y [d], yd [d])`` (copies). Within a hand-over: ``y_before + s delta`` and its velocity
        ``yd_before + s delta_dot + s_dot delta`` (see :meth:`change_weights`)."""
        y, yd = self._y.copy(), self._z * self.omega
        change = self._change
        if change is None:
            return y, yd
        ramp = handover_ramp(self.time, change.start, change.width)
        rate = handover_ramp_rate(self.time, change.start, change.width)
        return y + ramp * change.y, yd + ramp * self.omega * change.z + rate * change.y

    @property
    def y(self) -> np.ndarray:
        """Current position ``[d]`` (a copy; see :attr:`state`)."""
        return self.state[0]

    @property
    def handover_window(self) -> tuple[float, float] | None:
        """``(start, end)`` (s since the start) of the scheduled or running hand-over of :meth:`change_weights`;
        ``None`` when there is none."""
        change = self._change
        return None if change is None else (change.start, change.start + change.width)

    def request_stop(self, exit_phase: float | None = None, goal: np.ndarray | None = None) -> float:
        """End the movement: leave the cycle at the next demonstrated exit phase (or ``exit_phase``, rad) from
        now on and come to rest at ``goal [d]`` (default: the demonstrated goal, moved with the anchor).
        Returns the exit time (s since the start). Needs a DMP fitted with :func:`rdmp_gym.dmp.stopping.fit_ending`."""
        if self.stop is not None:
            raise ValueError("request_stop: a stop has already been requested")
        start = self.dmp.transients[self.transient]
        self.stop = self.dmp._stop_plan(StopRequest(self.time, exit_phase, goal), start, self.canonical.tempo,
                                        self.anchor[None], self.dmp.amplitude[None])
        self._drive.reset()      # the open-loop input from now on includes the stop
        if self._change is not None:
            self._change.drive.reset()
        return self.stop.exit_time

    def change_weights(self, weights: np.ndarray, at: float | None = None, handover: float = DEFAULT_HANDOVER
                       ) -> float:
        """Hand the movement over to the forcing weights ``weights [d, D]`` (the layout of
        :attr:`RhythmicDMP.weights`: periodic first, then each transient's) within ``handover`` periods, as
        :func:`~rdmp_gym.dmp.cycles.rollout_cycles` hands one cycle over to the next.

        The hand-over starts at the next cycle start at or after :attr:`time`
        (:func:`~rdmp_gym.dmp.cycles.next_cycle_start`; a request just after a crossing is served at the next one),
        or at ``at`` (s since the start, not in the past). Up to then the path is unchanged; from the end of the
        window on the stepper is the new weights' own integrator (:attr:`dmp` has them). Weights equal to the
        current ones change nothing. One change at a time: a request while one is scheduled or running
        (:attr:`handover_window`) is refused. A stop (:meth:`request_stop`) may be requested before or after.
        Returns the hand-over's start (s since the start).
        """
        if self._change is not None:
            start, end = self.handover_window
            raise ValueError(f"change_weights: a change is already scheduled (hand-over from {start:g} s to {end:g} s);"
                             " request the next one once it has ended")
        dmp = self.dmp.with_weights(weights)
        width = handover_width(self.dmp, handover, self.canonical.tempo)
        start = self._handover_start(at)
        if not np.array_equal(dmp.weights, self.dmp.weights):
            self._change = self._catch_up(dmp, start, width)
        return start

    def _handover_start(self, at: float | None) -> float:
        """The start (s) of a hand-over requested now for ``at`` (``None``: the next cycle start)."""
        if at is None:
            return next_cycle_start(self.dmp, self.time, self.transient, self.canonical.tempo)
        at = float(as_finite_array(at, "at", ndim=0))
        if at < self.time:
            raise ValueError(f"at: expected a time (s) not before the stepper's time {self.time:g} s, got {at!r}")
        return at

    def _catch_up(self, dmp: RhythmicDMP, start: float, width: float) -> _Change:
        """The change to ``dmp``'s weights, its response to the difference of the inputs integrated from rest at the
        movement's start up to now (the same first-order-hold discretisation as the steps)."""
        offsets = None if self.start_offsets is None else dmp._blend_offsets(self.transient, *self._start,
                                                                             self.canonical.tempo, self.anchor)
        drive = _Blocks(lambda times: self._open_loop(times, dmp.weights, offsets)
                        - self._open_loop(times, self.dmp.weights, self.start_offsets), self.dt, self.BLOCK)
        zeros = np.zeros(self.dmp.n_dims)
        y, z = self.system.rollout(self.omega * drive.compute(np.arange(self.steps + 1) * self.dt), zeros, zeros)
        return _Change(dmp, offsets, start, width, drive, y[-1], z[-1])

    def _advance(self, y: np.ndarray, z: np.ndarray, drive: _Blocks, c: np.ndarray | float
                 ) -> tuple[np.ndarray, np.ndarray]:
        """``(y, z) [d]`` one step on, driven by ``drive`` plus the coupling ``c`` held over the step."""
        u_now = self.omega * (drive(self.steps) + c)
        u_next = self.omega * (drive(self.steps + 1) + c)
        return self.system.step(y, z, u_now, u_next)

    def step(self, coupling: np.ndarray | object | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Advance by ``dt``; returns the new ``(y [d], yd [d])``.

        ``coupling``: ``c [d]`` in the units of the forcing term, or an object with a method
        ``acceleration(y, yd) -> [d]`` (m/s^2, e.g. :class:`rdmp_gym.dmp.coupling.ObstacleAvoidance`), applied as
        ``c = acceleration / Omega^2`` at the current state. Within a hand-over it acts on the stepper's own
        state, not on the response to the change."""
        if hasattr(coupling, "acceleration"):
            coupling = coupling.acceleration(*self.state) / self.omega**2
        c = np.zeros(self.dmp.n_dims) if coupling is None else as_finite_array(coupling, "coupling", ndim=1)
        if c.size != self.dmp.n_dims:
            raise ValueError(f"coupling: expected {self.dmp.n_dims} values, got {c.size}")
        self._y, self._z = self._advance(self._y, self._z, self._drive, c)
        change = self._change
        if change is not None:
            change.y, change.z = self._advance(change.y, change.z, change.drive, 0.0)
        self.steps += 1
        if change is not None and handover_ramp(self.time, change.start, change.width) >= 1.0:
            self._finish_change()
        return self.state

    def _finish_change(self) -> None:
        """End the hand-over: the response to the change joins the stepper's own state, the new weights drive it."""
        change, self._change = self._change, None
        self._y, self._z = self._y + change.y, self._z + change.z
        self.dmp, self.start_offsets = change.dmp, change.offsets
        self._drive.reset()
