"""The rhythmic DMP with transients (Ernesti et al. 2012): fit, rollout, step, parameters."""

from __future__ import annotations

import logging
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace
from functools import lru_cache
from pathlib import Path

import numpy as np

from .basis import BasisSet, Fading, normalize, periodic_width, transient_basis_along_path
from .canonical import CanonicalSystem
from .demonstrations import Demonstration
from .fitting import FIT_METHODS, fit_weights, forcing_target, smooth_derivatives
from .parameters import ParameterLayout
from .segmentation import Segmentation, phase_shift, segment
from .stopping import Ending, StopPlan, plan_stop
from .transformation import TransformationSystem
from .validation import as_finite_array, check_positive, check_time_grid

__all__ = ["DMPStepper", "RhythmicDMP", "TransientStart"]

logger = logging.getLogger(__name__)

GroupSelection = str | Iterable[str] | None


@dataclass(frozen=True)
class TransientStart:
    """One encoded transient: where the canonical system starts and where the demonstration started.

    Attributes:
        phi0, r0: initial condition of the canonical system, ``init_T(entrance_phase, mu1)``.
        length: transient length T_k of the demonstration (s).
        entrance_phase: phase at which the transient enters the periodic pattern (rad).
        start: ``[d]`` position of the demonstration at its first sample.
        start_velocity: ``[d]`` velocity of the demonstration at its first sample.
    """

    phi0: float
    r0: float
    length: float
    entrance_phase: float
    start: np.ndarray
    start_velocity: np.ndarray


def start_fade(elapsed: np.ndarray, length: float) -> np.ndarray:
    """Weight ``[T]`` of the start offset under ``start_blend``: 1 at the start, 0 from ``length`` on
    (a minimum-jerk profile, C2)."""
    u = np.clip(elapsed / length, 0.0, 1.0)
    return 1.0 - u**3 * (10.0 - 15.0 * u + 6.0 * u**2)


@lru_cache(maxsize=64)
def _transformation(omega: float, dt: float, alpha_z: float) -> TransformationSystem:
    return TransformationSystem(omega, dt, alpha_z)


def _as_demos(demos: Demonstration | Sequence[Demonstration]) -> list[Demonstration]:
    demos = [demos] if isinstance(demos, Demonstration) else list(demos)
    if not demos:
        raise ValueError("demos: expected at least one Demonstration")
    for index, demo in enumerate(demos):
        if not isinstance(demo, Demonstration):
            raise TypeError(f"demos[{index}]: expected a Demonstration, got {type(demo).__name__}")
        if demo.n_dims != demos[0].n_dims:
            raise ValueError(f"demos[{index}]: has {demo.n_dims} dimensions, demos[0] has {demos[0].n_dims}")
    return demos


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
        alpha_z: damping gain of the transformation system (``beta_z = alpha_z / 4``).
        amplitude: ``[d]`` factors that scale the movement about the anchor (forcing term and default
            start); ones by default. A learnable parameter group, like the weights.
        ending: the encoded end of the movement (:mod:`rdmp_gym.stopping`), or ``None``.
    """

    def __init__(self, canonical: CanonicalSystem, basis: BasisSet, weights: np.ndarray,
                 transients: Sequence[TransientStart], anchor: np.ndarray, alpha_z: float = 25.0,
                 amplitude: np.ndarray | None = None, ending: Ending | None = None) -> None:
        self.canonical = canonical
        self.basis = basis
        self.weights = as_finite_array(weights, "weights", ndim=2)
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
        self.ending = ending
        self.layout = ParameterLayout(self.n_dims, basis.n_periodic, basis.transient_sizes,
                                      0 if ending is None else ending.weights.size)

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
    def fit(cls, demos: Demonstration | Sequence[Demonstration], n_periodic: int = 40,
            n_transient: int | Sequence[int] = 40, method: str = "ridge", *,
            segmentations: Sequence[Segmentation] | None = None, period: float | None = None,
            alpha_z: float = 25.0, mu: float = 1.0, eta: float = 35.0, alpha: float = 1.0 / 6.0,
            beta: float = 1.0 / 1000.0, mu1_factor: float = 1.2, fading_time: float | None = None,
            delta: float = 1e-3, periodic_overlap: float = 0.5, transient_overlap: float = 0.5,
            smoothing: float = 0.15, regularization: float = 1e-6) -> RhythmicDMP:
        """Fit a DMP to one or more demonstrations that share a periodic pattern (paper III-E, V-A).

        Args:
            demos: a :class:`Demonstration` or K of them (one transient each), all with d dimensions.
            n_periodic: periodic basis functions N.
            n_transient: transient basis functions per transient (an int or K ints).
            method: ``"lwr"`` (the paper's (11)/(12)) or ``"ridge"`` (global least squares, default).
            segmentations: per demonstration; estimated with :func:`segment` when omitted.
            period: common period (s); the mean of the segmentations' periods when omitted.
            alpha_z: transformation-system gain.
            mu, eta, alpha, beta: canonical-system constants (the paper's defaults).
            mu1_factor: ``mu1 = mu1_factor * mu`` (1.2 in the paper).
            fading_time: t_f (s), the overlap of transient and periodic basis; default
                ``min(period, shortest transient) / 4``.
            delta: support threshold of the fades.
            periodic_overlap, transient_overlap: height at which neighbouring basis functions cross.
            smoothing: Savitzky-Golay window (s) for the demonstration's derivatives.
            regularization: relative ridge penalty.
        """
        demos = _as_demos(demos)
        if method not in FIT_METHODS:
            raise ValueError(f"method: expected one of {FIT_METHODS}, got {method!r}")
        if int(n_periodic) < 2:
            raise ValueError(f"n_periodic: expected at least 2, got {n_periodic}")
        sizes = [int(n_transient)] * len(demos) if np.ndim(n_transient) == 0 else [int(m) for m in n_transient]
        if len(sizes) != len(demos) or min(sizes) < 1:
            raise ValueError(f"n_transient: expected a positive int or {len(demos)} positive ints, got {n_transient!r}")
        if segmentations is None:
            segmentations = [segment(demo, period=period) for demo in demos]
        elif len(segmentations) != len(demos):
            raise ValueError(f"segmentations: expected {len(demos)}, got {len(segmentations)}")
        common_period = (check_positive(period, "period") if period is not None
                         else float(np.mean([seg.period for seg in segmentations])))
        canonical = CanonicalSystem(common_period, mu=mu, eta=eta, alpha=alpha, beta=beta)
        anchor = np.mean([seg.anchor for seg in segmentations], axis=0)
        lengths = [check_positive(seg.transient_length, "segmentations.transient_length")
                   for seg in segmentations]

        reference = int(np.argmin(lengths))
        entrance = [canonical.omega * phase_shift(demos[reference], segmentations[reference], demo, seg,
                                                  common_period) if k != reference else 0.0
                    for k, (demo, seg) in enumerate(zip(demos, segmentations, strict=True))]
        mu1 = mu1_factor * mu
        t_f = (check_positive(fading_time, "fading_time") if fading_time is not None
               else 0.25 * min(common_period, min(lengths)))
        if t_f >= min(lengths):
            raise ValueError(f"fading_time: must be shorter than the shortest transient ({min(lengths):.3g} s)")
        fading = Fading(mu1=mu1, mu2=canonical.init_T(t_f, 0.0, mu1)[1], delta=delta)

        inits = [canonical.init_T(length, phase, mu1) for length, phase in zip(lengths, entrance, strict=True)]
        paths = [transient_basis_along_path(canonical, phi0, r0, length - 0.5 * t_f, m,
                                            transient_overlap, delta)
                 for (phi0, r0), length, m in zip(inits, lengths, sizes, strict=True)]
        basis = BasisSet(
            periodic_centres=2.0 * np.pi * np.arange(n_periodic) / n_periodic,
            periodic_widths=np.full(n_periodic, periodic_width(n_periodic, periodic_overlap)),
            transient_centres=np.concatenate([centres for centres, _ in paths]),
            transient_widths=np.concatenate([widths for _, widths in paths]),
            transient_sizes=tuple(sizes), fading=fading)

        activations, targets, transients = [], [], []
        for demo, (phi0, r0), length, phase in zip(demos, inits, lengths, entrance, strict=True):
            Y, Yd, Ydd = smooth_derivatives(demo.Y, demo.dt, smoothing)
            phi, r = canonical.state(demo.t - demo.t[0], phi0, r0)
            activations.append(basis.activations(phi, r))
            targets.append(forcing_target(Y, Yd, Ydd, anchor, canonical.omega, alpha_z))
            transients.append(TransientStart(phi0, r0, length, phase, Y[0].copy(), Yd[0].copy()))
        weights = fit_weights(np.concatenate(activations), np.concatenate(targets), method, regularization)
        logger.info("fitted %d transient(s), N=%d, M=%s, period %.4g s, method %s",
                    len(demos), n_periodic, sizes, common_period, method)
        return cls(canonical, basis, weights.T, transients, anchor, alpha_z)

    # ------------------------------------------------------------------ rollouts
    def _check_transient(self, transient: int) -> int:
        if not isinstance(transient, (int, np.integer)) or not 0 <= transient < self.n_transients:
            raise ValueError(f"transient: expected an index in [0, {self.n_transients}), got {transient!r}")
        return int(transient)

    def _tempo(self, tempo: float | None) -> float:
        """The requested tempo, or the canonical system's when ``None``."""
        return self.canonical.tempo if tempo is None else check_positive(tempo, "tempo")

    def _vector(self, value: object, default: np.ndarray, name: str, batch: int) -> np.ndarray:
        """``value`` (``[d]`` or ``[B, d]``, or None for ``default``) broadcast to ``[B, d]``."""
        array = default if value is None else as_finite_array(value, name, ndim=(1, 2))
        if array.shape[-1] != self.n_dims or (array.ndim == 2 and array.shape[0] != batch):
            raise ValueError(f"{name}: expected shape ({self.n_dims},) or ({batch}, {self.n_dims}), got {array.shape}")
        return np.broadcast_to(array, (batch, self.n_dims))

    def _simulate(self, t: np.ndarray, weights: np.ndarray, inits: np.ndarray, anchors: np.ndarray,
                  amplitudes: np.ndarray, y0: np.ndarray, yd0: np.ndarray, tempo: float,
                  transform: np.ndarray | None, start_offset: np.ndarray | None = None, fade_length: float = 1.0,
                  stop: StopPlan | None = None, stop_weights: np.ndarray | None = None
                  ) -> tuple[np.ndarray, np.ndarray]:
        """Open-loop integration of B parameter sets: weights ``[B, d, D]``, inits ``[B, 2]``,
        anchors/amplitudes/y0/yd0 ``[B, d]`` -> positions and velocities ``[B, T, d]``. The forcing term is
        multiplied by ``M diag(amplitude)``. A ``start_offset [B, d]`` moves the anchor at the start and fades
        out over ``fade_length`` seconds (``start_blend``). A ``stop`` (with ``stop_weights [B, d, S]``) ends
        the movement at ``stop.goal [B, d]``."""
        t = check_time_grid(t, "t")
        elapsed = t - t[0]
        dt = float(elapsed[-1] / (elapsed.size - 1))
        canonical = replace(self.canonical, tempo=tempo)
        unique, inverse = np.unique(inits, axis=0, return_inverse=True)
        phis, radii = canonical.state(elapsed, unique[:, 0], unique[:, 1])              # [U, T] each
        forcing = np.empty((weights.shape[0], t.size, self.n_dims))
        for index, (phi, r) in enumerate(zip(phis, radii, strict=True)):
            members = np.flatnonzero(inverse.ravel() == index)
            if stop is None:
                forcing[members] = self.basis.forcing(phi, r, weights[members])
            else:
                forcing[members] = self.ending.forcing(self.basis, phi, r, (elapsed - stop.exit_time) * tempo,
                                                       stop.rotation, weights[members], stop_weights[members])
        forcing *= amplitudes[:, None, :]
        if transform is not None:
            forcing = forcing @ transform.T
        base = anchors
        if start_offset is not None:
            anchors = anchors[:, None, :] + start_fade(elapsed, fade_length)[:, None] * start_offset[:, None, :]
        if stop is not None:
            blend = self.ending.anchor_blend((elapsed - stop.exit_time) * tempo)[:, None]
            anchors = (anchors if anchors.ndim == 3 else anchors[:, None, :]) + blend * (stop.goal - base)[:, None, :]
        omega = canonical.omega * tempo
        system = _transformation(omega, dt, self.alpha_z)
        y, z = system.rollout(system.input(anchors, forcing), y0, yd0 / omega)
        return y, z * omega

    def _start(self, k: int, y0: object, yd0: object, tempo: float, anchors: np.ndarray, amplitudes: np.ndarray,
               start_blend: bool, transform: np.ndarray | None = None
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """Initial ``(y0, yd0)`` ``[B, d]`` of transient k for anchors and amplitudes ``[B, d]``.

        The defaults are its demonstration's start and start velocity, transformed like the whole movement
        (``g + M diag(amplitude) (start - g)``, g the fitted anchor). Under ``start_blend`` also the offset of
        ``y0`` from that start carried along with the anchor, ``anchor + M diag(amplitude) (start - g)``."""
        start = self.transients[k]
        relative_start = amplitudes * (start.start - self.anchor)                       # [B, d]
        default_yd0 = amplitudes * start.start_velocity * tempo / self.canonical.tempo
        if transform is not None:   # the whole demonstrated movement is transformed about the fitted anchor
            relative_start, default_yd0 = relative_start @ transform.T, default_yd0 @ transform.T
        y0 = self._vector(y0, self.anchor + relative_start, "y0", anchors.shape[0])
        offset = y0 - (anchors + relative_start) if start_blend else None
        return y0, self._vector(yd0, default_yd0, "yd0", anchors.shape[0]), offset

    def rollout(self, t: np.ndarray, transient: int = 0, y0: np.ndarray | None = None,
                yd0: np.ndarray | None = None, anchor: np.ndarray | None = None, *,
                scale: float | np.ndarray = 1.0, rotation: float | np.ndarray | None = None,
                tempo: float | None = None, start_blend: bool = False, return_velocity: bool = False,
                stop_at: float | None = None, exit_phase: float | None = None, goal: np.ndarray | None = None
                ) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
        """Reproduce the movement: transient ``transient`` from its own initial condition, then the cycle.

        Args:
            t: ``[T]`` evenly spaced times; ``t[0]`` is the start of the movement.
            transient: index of the encoded transient (its canonical initial condition).
            y0, yd0: ``[d]`` start position/velocity (default: that transient's demonstration start).
            anchor: ``[d]`` new anchor g (default: the fitted one). The periodic part moves with it.
            scale: amplitude factor (a number or ``[d]``) of the movement about the anchor.
            rotation: an angle (rad, about the axis normal to dims 0 and 1) or an orthogonal ``[d, d]`` matrix.
                With ``scale``/``rotation`` the whole movement is transformed, ``y - g -> M (y - g)`` with
                ``M = R diag(scale)``: the default start becomes ``g + M (start - g)`` (g: the fitted anchor);
                the result is exact, and exact on the periodic part for any explicit ``y0``.
            tempo: speed factor (default: the canonical system's; 0.5 = half speed).
            start_blend: for a ``y0`` away from the demonstrated start (carried along with the anchor,
                ``anchor + M (start - g)``): shift the anchor by the offset at the start and fade the shift
                out over the transient (minimum jerk), so the movement starts at ``y0``, keeps the
                demonstrated transient's shape and joins the pattern smoothly. Without it the stiff
                spring closes the gap within about ``4 / (alpha_z Omega)`` seconds. The periodic part
                is the same either way.
            return_velocity: also return velocities.
            stop_at: end the movement: a stop requested at this time (s after ``t[0]``) leaves the cycle at the
                next demonstrated exit phase (or at ``exit_phase``, rad) and comes to rest at the goal (needs a DMP
                fitted with :func:`rdmp_gym.stopping.fit_ending`); a request during the start transient is served
                once the transient has reached the cycle.
            goal: ``[d]`` rest position of the stop (default: the demonstrated one, moved and transformed with
                the anchor like the periodic part).
        Returns:
            positions ``[T, d]`` (and velocities ``[T, d]``).
        """
        k = self._check_transient(transient)
        tempo = self._tempo(tempo)
        start = self.transients[k]
        transform = _transform_matrix(self.n_dims, scale, rotation)
        anchors = self._vector(anchor, self.anchor, "anchor", 1)
        amplitudes = self.amplitude[None]
        y0, yd0, offset = self._start(k, y0, yd0, tempo, anchors, amplitudes, start_blend, transform)
        inits = np.array([[start.phi0, start.r0]])
        stop = self._stop_plan(stop_at, exit_phase, goal, start, tempo, anchors, amplitudes, transform)
        y, yd = self._simulate(t, self.weights[None], inits, anchors, amplitudes, y0, yd0, tempo, transform,
                               offset, start.length / tempo, stop,
                               None if stop is None else self.ending.weights[None])
        return (y[0], yd[0]) if return_velocity else y[0]

    def _stop_plan(self, stop_at: float | None, exit_phase: float | None, goal: object, start: TransientStart,
                   tempo: float, anchors: np.ndarray, amplitudes: np.ndarray, transform: np.ndarray | None = None
                   ) -> StopPlan | None:
        """The stop requested by ``stop_at`` (``None``: no stop); default goals ``[B, d]`` move with the anchors.
        A request during the start transient of ``start`` is served once the transient has reached the cycle."""
        if stop_at is None:
            if exit_phase is not None or goal is not None:
                raise ValueError("stop_at: exit_phase and goal need a stop time")
            return None
        if self.ending is None:
            raise ValueError("stop_at: this DMP encodes no end of the movement; fit it with "
                             "rdmp_gym.stopping.fit_ending")
        relative = amplitudes * (self.ending.goal - self.anchor)
        if transform is not None:
            relative = relative @ transform.T
        goals = self._vector(goal, anchors + relative, "goal", anchors.shape[0])
        stop_at = float(as_finite_array(stop_at, "stop_at", ndim=0))
        if stop_at < 0.0:
            raise ValueError(f"stop_at: expected a time >= 0, got {stop_at!r}")
        return plan_stop(self.ending, max(stop_at, start.length / tempo), start.phi0, self.canonical.omega * tempo,
                         goals, exit_phase)

    def with_ending(self, ending: Ending | None) -> RhythmicDMP:
        """A copy of this DMP with another end of the movement (``None`` removes it)."""
        return RhythmicDMP(self.canonical, self.basis, self.weights, self.transients, self.anchor, self.alpha_z,
                           self.amplitude, ending)

    def rollout_batch(self, thetas: np.ndarray, t: np.ndarray, groups: GroupSelection = None,
                      transient: int = 0, y0: np.ndarray | None = None, yd0: np.ndarray | None = None,
                      anchor: np.ndarray | None = None, tempo: float | None = None,
                      start_blend: bool = False, stop_at: float | None = None,
                      exit_phase: float | None = None, goal: np.ndarray | None = None) -> np.ndarray:
        """Roll out B parameter vectors at once (the selected ``groups`` of each; the rest as fitted).

        Args:
            thetas: ``[B, P]`` parameter vectors, P = ``self.layout.size(groups)``.
            t: ``[T]`` evenly spaced times.
            groups: which parameter groups ``thetas`` holds (see :mod:`rdmp_gym.parameters`).
            transient, y0, yd0, anchor, tempo, start_blend, stop_at, exit_phase, goal: as in :meth:`rollout`;
                y0/yd0/anchor/goal may be ``[B, d]``. The stop starts at the same time for all B (their phases
                differ only where ``initial`` is selected; the exit follows transient ``transient``'s fitted phase).
        Returns:
            ``[B, T, d]`` positions.
        """
        k = self._check_transient(transient)
        thetas = as_finite_array(thetas, "thetas", ndim=2)
        weights, inits, anchors, amplitudes, stop_weights = self._decode(thetas, groups)
        batch = thetas.shape[0]
        if anchor is not None:
            if "anchor" in self.layout.resolve(groups):
                raise ValueError("anchor: given both as an argument and in thetas (group 'anchor')")
            anchors = self._vector(anchor, self.anchor, "anchor", batch)
        tempo = self._tempo(tempo)
        y0, yd0, offset = self._start(k, y0, yd0, tempo, anchors, amplitudes, start_blend)
        stop = self._stop_plan(stop_at, exit_phase, goal, self.transients[k], tempo, anchors, amplitudes)
        return self._simulate(t, weights, inits[:, k], anchors, amplitudes, y0, yd0, tempo, None,
                              offset, self.transients[k].length / tempo, stop, stop_weights)[0]

    def start(self, dt: float, transient: int = 0, y0: np.ndarray | None = None,
              yd0: np.ndarray | None = None, anchor: np.ndarray | None = None,
              tempo: float | None = None, start_blend: bool = False) -> DMPStepper:
        """An online integrator that advances by ``dt`` per :meth:`DMPStepper.step` (for feedback);
        arguments as in :meth:`rollout`."""
        k = self._check_transient(transient)
        tempo = self._tempo(tempo)
        anchors = self._vector(anchor, self.anchor, "anchor", 1)
        y0, yd0, offset = self._start(k, y0, yd0, tempo, anchors, self.amplitude[None], start_blend)
        return DMPStepper(self, check_positive(dt, "dt"), k, y0[0].copy(), yd0[0].copy(), anchors[0].copy(), tempo,
                          None if offset is None else offset[0])

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
        """The selected groups as one flat vector ``[P]`` (order: see :mod:`rdmp_gym.parameters`)."""
        parts = []
        for name in self.layout.resolve(groups):
            if name == "periodic":
                parts.append(self.weights[:, : self.basis.n_periodic].ravel())
            elif name.startswith("transient:"):
                parts.append(self.weights[:, self._transient_columns(int(name[10:]))].ravel())
            elif name.startswith("initial:"):
                start = self.transients[int(name[8:])]
                parts.append(np.array([start.phi0, start.r0]))
            elif name == "anchor":
                parts.append(self.anchor.copy())
            elif name == "stop":
                parts.append(self.ending.weights.ravel())
            else:
                parts.append(self.amplitude.copy())
        return np.concatenate(parts)

    def _transient_columns(self, k: int) -> slice:
        offset = self.basis.n_periodic + sum(self.basis.transient_sizes[:k])
        return slice(offset, offset + self.basis.transient_sizes[k])

    def _decode(self, thetas: np.ndarray, groups: GroupSelection
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
        """``thetas [B, P]`` -> weights ``[B, d, D]``, initial conditions ``[B, K, 2]``, anchors and
        amplitudes ``[B, d]``, stop weights ``[B, d, S]`` (``None`` without an ending)."""
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
        for name, part in slices.items():
            values = thetas[:, part]
            if name == "periodic":
                weights[:, :, : self.basis.n_periodic] = values.reshape(batch, self.n_dims, -1)
            elif name.startswith("transient:"):
                weights[:, :, self._transient_columns(int(name[10:]))] = values.reshape(batch, self.n_dims, -1)
            elif name.startswith("initial:"):
                if np.any(values[:, 1] <= 0.0):
                    raise ValueError(f"theta: the initial radius r0 of {name} must be > 0")
                inits[:, int(name[8:])] = values
            elif name == "anchor":
                anchors = values.copy()
            elif name == "stop":
                stop_weights = values.reshape(batch, self.n_dims, -1)
            else:
                amplitudes = values.copy()
        return weights, inits, anchors, amplitudes, stop_weights

    def with_params(self, theta: np.ndarray, groups: GroupSelection = None) -> RhythmicDMP:
        """A new DMP whose selected groups are replaced by ``theta [P]``."""
        theta = as_finite_array(theta, "theta", ndim=1)
        weights, inits, anchors, amplitudes, stop_weights = self._decode(theta[None], groups)
        transients = [replace(start, phi0=float(phi0), r0=float(r0))
                      for start, (phi0, r0) in zip(self.transients, inits[0], strict=True)]
        ending = None if self.ending is None else self.ending.with_weights(stop_weights[0])
        return RhythmicDMP(self.canonical, self.basis, weights[0], transients, anchors[0], self.alpha_z,
                           amplitudes[0], ending)

    def param_time_weights(self, t: np.ndarray, groups: GroupSelection = None, transient: int = 0,
                           stop_at: float | None = None) -> np.ndarray:
        """How active each parameter is at each time, ``[T, P]`` in [0, 1] (PI²'s time weighting).

        A weight's entry is its basis function's normalised activation along the path of transient
        ``transient`` (with the stop requested at ``stop_at``, if given); the initial condition of that transient,
        the anchor and the amplitude act throughout (1); another transient's initial condition does not act (0),
        nor do the stop weights without a stop.
        """
        k = self._check_transient(transient)
        start = self.transients[k]
        elapsed = as_finite_array(t, "t", ndim=1) - np.min(t)
        phi, r = self.canonical.state(elapsed, start.phi0, start.r0)
        stop = self._stop_plan(stop_at, None, None, start, self.canonical.tempo, self.anchor[None],
                               self.amplitude[None])
        if stop is None:
            activation = self.basis.normalized(phi, r)                               # [T, D]
        else:
            activation = normalize(self.ending.mixture(self.basis, phi, r, (elapsed - stop.exit_time)
                                                       * self.canonical.tempo, stop.rotation))   # [T, D + S]
        columns = []
        for name in self.layout.resolve(groups):
            if name == "periodic":
                block = activation[:, : self.basis.n_periodic]
            elif name.startswith("transient:"):
                block = activation[:, self._transient_columns(int(name[10:]))]
            elif name == "stop" and stop is not None:
                block = activation[:, self.basis.n_basis:]
            else:
                acts = name != "stop" and (not name.startswith("initial:") or int(name[8:]) == k)
                columns.append(np.full((phi.size, self.layout.sizes[name]), float(acts)))
                continue
            columns.append(np.tile(block, (1, self.n_dims)))
        return np.concatenate(columns, axis=1)

    # ------------------------------------------------------------------ persistence
    def save(self, path: str | Path) -> None:
        """Write the DMP to a JSON file (format: :mod:`rdmp_gym.serialization`)."""
        from .serialization import save_dmp

        save_dmp(self, path)

    @classmethod
    def load(cls, path: str | Path) -> RhythmicDMP:
        """Read a DMP written by :meth:`save`."""
        from .serialization import load_dmp

        return load_dmp(path)

    def __repr__(self) -> str:
        return (f"RhythmicDMP(n_dims={self.n_dims}, period={self.period:.4g}, n_periodic={self.basis.n_periodic}, "
                f"transient_sizes={self.basis.transient_sizes})")


class DMPStepper:
    """Online integration of a :class:`RhythmicDMP`, one sample at a time, with an optional coupling term.

    Uses the same exact first-order-hold step as :meth:`RhythmicDMP.rollout`, so with no coupling
    both produce the same trajectory. A coupling term ``c [d]`` is added to the forcing term inside
    (4) and held over the step: ``dz/dt = Omega (alpha_z (beta_z (g - y) - z) + f + c)``. The
    canonical system does not depend on ``y``, so the open-loop part of the input (anchor and forcing
    term) is computed ahead in blocks of ``BLOCK`` samples; a step then costs one 2x2 update.
    """

    BLOCK = 256

    def __init__(self, dmp: RhythmicDMP, dt: float, transient: int, y0: np.ndarray, yd0: np.ndarray,
                 anchor: np.ndarray, tempo: float, start_offset: np.ndarray | None = None) -> None:
        self.dmp, self.dt, self.transient, self.anchor = dmp, dt, transient, anchor
        self.start_offset = np.zeros_like(anchor) if start_offset is None else start_offset
        self.fade_length = dmp.transients[transient].length / tempo
        self.canonical = replace(dmp.canonical, tempo=tempo)
        self.omega = self.canonical.omega * tempo
        self.system = _transformation(self.omega, dt, dmp.alpha_z)
        self.steps = 0
        self.y, self.z = y0, yd0 / self.omega
        self._block_index, self._block = -1, np.empty((0, dmp.n_dims))
        self.stop: StopPlan | None = None

    @property
    def time(self) -> float:
        """Time since the start (s)."""
        return self.steps * self.dt

    def _drive(self, step: int) -> np.ndarray:
        """Open-loop part of the input at sample ``step``, ``alpha_z beta_z g(t) + f(t)`` ``[d]``."""
        index, offset = divmod(step, self.BLOCK)
        if index != self._block_index:
            start = self.dmp.transients[self.transient]
            times = (index * self.BLOCK + np.arange(self.BLOCK)) * self.dt
            phi, r = self.canonical.state(times, start.phi0, start.r0)
            anchor = self.anchor + start_fade(times, self.fade_length)[:, None] * self.start_offset
            if self.stop is None:
                forcing = self.dmp.basis.forcing(phi, r, self.dmp.weights)
            else:
                tau = (times - self.stop.exit_time) * self.canonical.tempo
                forcing = self.dmp.ending.forcing(self.dmp.basis, phi, r, tau, self.stop.rotation, self.dmp.weights,
                                                  self.dmp.ending.weights)
                anchor = anchor + self.dmp.ending.anchor_blend(tau)[:, None] * (self.stop.goal[0] - self.anchor)
            self._block = (self.dmp.alpha_z * self.system.beta_z * anchor + self.dmp.amplitude * forcing)
            self._block_index = index
        return self._block[offset]

    @property
    def state(self) -> tuple[np.ndarray, np.ndarray]:
        """Current ``(y [d], yd [d])`` (copies)."""
        return self.y.copy(), self.z * self.omega

    def request_stop(self, exit_phase: float | None = None, goal: np.ndarray | None = None) -> float:
        """End the movement: leave the cycle at the next demonstrated exit phase (or ``exit_phase``, rad) from
        now on and come to rest at ``goal [d]`` (default: the demonstrated goal, moved with the anchor).
        Returns the exit time (s since the start). Needs a DMP fitted with :func:`rdmp_gym.stopping.fit_ending`."""
        if self.stop is not None:
            raise ValueError("request_stop: a stop has already been requested")
        start = self.dmp.transients[self.transient]
        self.stop = self.dmp._stop_plan(self.time, exit_phase, goal, start, self.canonical.tempo,
                                        self.anchor[None], self.dmp.amplitude[None])
        self._block_index = -1      # the open-loop input from now on includes the stop
        return self.stop.exit_time

    def step(self, coupling: np.ndarray | object | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Advance by ``dt``; returns the new ``(y [d], yd [d])``.

        ``coupling``: ``c [d]`` in the units of the forcing term, or an object with a method
        ``acceleration(y, yd) -> [d]`` (m/s^2, e.g. :class:`rdmp_gym.coupling.ObstacleAvoidance`), applied as
        ``c = acceleration / Omega^2`` at the current state."""
        if hasattr(coupling, "acceleration"):
            coupling = coupling.acceleration(*self.state) / self.omega**2
        c = np.zeros(self.dmp.n_dims) if coupling is None else as_finite_array(coupling, "coupling", ndim=1)
        if c.size != self.dmp.n_dims:
            raise ValueError(f"coupling: expected {self.dmp.n_dims} values, got {c.size}")
        u_now = self.omega * (self._drive(self.steps) + c)
        u_next = self.omega * (self._drive(self.steps + 1) + c)
        self.y, self.z = self.system.step(self.y, self.z, u_now, u_next)
        self.steps += 1
        return self.state
