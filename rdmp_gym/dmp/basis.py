"""Periodic and transient basis functions on the phase plane, with fading (paper eqs. (5)-(9)).

Periodic (on the limit cycle):  ``phi_i(phi, r) = g(r) exp(v_i (cos(phi - c_i) - 1))``
Transient (along a canonical path): ``psi_j(phi, r) = a(r) exp(-vbar_j |pol(phi, r) - q_j|^2)``

``g`` is 1 up to ``mu1`` and fades to ``delta`` at ``mu2``; ``a`` is 1 from ``mu2`` and fades to
``delta`` at ``mu1``; both use ``exp(-v_tilde (r - mu_x)**k)`` (:class:`FadeBand`, whose mirror image gates the
stop: :class:`rdmp_gym.dmp.ending.StopFading`).

The forcing term (5) is the normalised mixture ``sum_b Psi_b w_b / sum_b Psi_b``. Where a perturbed
canonical path leaves every support, the raw sum underflows and the bare mixture jumps between whichever
far-away basis function happens to be least small (or becomes 0/0). We divide by ``sum_b Psi_b + floor``
instead (``Fading.floor``): on the encoded paths the activations sum to about 1 and the floor changes
nothing the fit does not absorb; where they sum to much less than the floor the forcing term fades
smoothly to zero. The default of :class:`Fading` (1e-10) is the old, nearly bare mixture kept for saved
DMPs; :meth:`RhythmicDMP.fit` uses a larger one (:data:`rdmp_gym.dmp.fitting.HANDOVER_FLOOR`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..validation import check_nonnegative, check_positive
from .canonical import CanonicalSystem

__all__ = ["GATE_FLOOR", "SMOOTH_FLOOR", "BasisSet", "FadeBand", "Fading", "normalize", "periodic_width",
           "transient_basis_along_path", "transient_times", "von_mises"]

NORMALISATION_EPSILON = 1e-10
"""Added to the sum of activations in the normalised mixture (5) by default; keeps it finite off every support."""

SMOOTH_FLOOR = 1e-2
"""A floor that fades the mixture to 0 wherever the activations sum to much less than 1 %."""

FORCING_BLOCK = 1 << 15
"""Time samples per block in :meth:`BasisSet.forcing` (bounds the ``[T, D]`` activations held at once)."""

GATE_FLOOR = 1e-16
"""Gate values below this are exactly 0, so a family of basis functions can be skipped where it is
off (a change of at most 1e-16 in any activation, far below the float64 resolution of the mixture)."""


class FadeBand:
    """Two gates that hand one family of basis functions over to another across the radii ``[inner, outer]``
    (the fading of eqs. (8)-(9)), for the start and the stop alike.

    :meth:`inner_gate` is 1 for ``r <= inner`` and fades above it; :meth:`outer_gate` is 1 for ``r >= outer`` and
    fades below it; each is ``delta`` at the other edge: ``exp(-v_tilde d**k)`` of the distance ``d`` past its own
    edge, exactly 0 below :data:`GATE_FLOOR`. A subclass names the edges (``inner``, ``outer``) and holds ``k``
    and ``delta``: :class:`Fading` (the start: periodic family inside ``mu1``, transient family outside ``mu2``)
    and :class:`rdmp_gym.dmp.ending.StopFading` (the stop: stop family inside ``nu2``, periodic family outside
    ``nu1``).
    """

    @property
    def inner(self) -> float:
        """The radius up to which :meth:`inner_gate` is 1."""
        raise NotImplementedError

    @property
    def outer(self) -> float:
        """The radius from which :meth:`outer_gate` is 1 (> ``inner``)."""
        raise NotImplementedError

    @property
    def v_tilde(self) -> float:
        """Fading steepness chosen so that each gate is ``delta`` at the other edge."""
        return -np.log(self.delta) / (self.outer - self.inner) ** self.k

    def inner_gate(self, r: np.ndarray) -> np.ndarray:
        """1 for ``r <= inner``, fading above; same shape as ``r``."""
        return self._fade(np.maximum(r - self.inner, 0.0))

    def outer_gate(self, r: np.ndarray) -> np.ndarray:
        """1 for ``r >= outer``, fading below; same shape as ``r``."""
        return self._fade(np.maximum(self.outer - r, 0.0))

    def _fade(self, distance: np.ndarray) -> np.ndarray:
        gate = np.exp(-self.v_tilde * distance**self.k)
        return np.where(gate < GATE_FLOOR, 0.0, gate)


@dataclass(frozen=True)
class Fading(FadeBand):
    """The fading functions ``g`` (periodic gate) and ``a`` (transient gate) of eqs. (8)-(9): a
    :class:`FadeBand` across ``[mu1, mu2]``.

    Args:
        mu1: radius below which only the periodic basis is active (the paper uses 1.2 mu).
        mu2: radius above which only the transient basis is active (> mu1).
        k: exponent of the fade (k = 4 makes the forcing term smooth).
        delta: value of ``g(mu2)`` and ``a(mu1)`` (the support threshold, about 1e-3).
        floor: added to the sum of activations in the mixture (5), so that it fades where they are small.
    """

    mu1: float
    mu2: float
    k: int = 4
    delta: float = 1e-3
    floor: float = NORMALISATION_EPSILON

    def __post_init__(self) -> None:
        check_positive(self.mu1, "mu1")
        check_positive(self.delta, "delta")
        if not self.mu2 > self.mu1:
            raise ValueError(f"mu2: must exceed mu1 = {self.mu1:g}, got {self.mu2!r}")
        check_positive(self.floor, "floor")
        if not 0.0 < self.delta < 1.0:
            raise ValueError(f"delta: must lie in (0, 1), got {self.delta!r}")

    @property
    def inner(self) -> float:
        return self.mu1

    @property
    def outer(self) -> float:
        return self.mu2

    def periodic_gate(self, r: np.ndarray) -> np.ndarray:
        """``g(r)``: 1 for r <= mu1, fading above; same shape as ``r``."""
        return self.inner_gate(r)

    def transient_gate(self, r: np.ndarray) -> np.ndarray:
        """``a(r)``: 1 for r >= mu2, fading below; same shape as ``r``."""
        return self.outer_gate(r)


def normalize(activations: np.ndarray, floor: float = NORMALISATION_EPSILON) -> np.ndarray:
    """Normalised activations ``Psi / (sum Psi + floor)`` along the last axis, ``[..., D]`` (the mixture (5))."""
    return activations / (activations.sum(axis=-1, keepdims=True) + floor)


def von_mises(phi: np.ndarray, centres: np.ndarray, widths: np.ndarray) -> np.ndarray:
    """Periodic bumps ``h_i(phi) = exp(v_i (cos(phi - c_i) - 1))``: ``phi [..., T]`` -> ``[..., T, N]``."""
    phi = phi[..., None]
    return np.exp(widths * (np.cos(phi) * np.cos(centres) + np.sin(phi) * np.sin(centres) - 1.0))


def periodic_width(n_periodic: int, overlap: float = 0.5) -> float:
    """Width ``v`` that makes neighbouring periodic basis functions cross at height ``overlap``."""
    if not 0.0 < overlap < 1.0:
        raise ValueError(f"periodic_overlap: must lie in (0, 1), got {overlap!r}")
    return float(np.log(1.0 / overlap) / (1.0 - np.cos(np.pi / n_periodic)))


def transient_times(span: float, n_basis: int, lead: float = 0.0) -> np.ndarray:
    """Times ``[M]`` (s from the start of the path) of ``n_basis`` transient centres: evenly spaced, the last at
    ``span`` and the first ``lead`` spacings before the start (at most ``n_basis - 2``: one centre stays after it).

    A centre before the start makes the mixture (5) two-sided there: with the first centre at the start, the
    normalised mixture is flat on its outer side and cannot follow the slope of the forcing term the start needs
    (the fit then rings at the basis spacing over the first tenth of a second).
    """
    if n_basis == 1:
        return np.array([0.0])
    lead = min(check_nonnegative(lead, "transient_lead"), n_basis - 2.0)
    spacing = span / (n_basis - 1.0 - lead)
    return spacing * (np.arange(n_basis) - lead)


def transient_basis_along_path(canonical: CanonicalSystem, phi0: float, r0: float, span: float,
                               n_basis: int, overlap: float = 0.5, delta: float = 1e-3, lead: float = 0.0
                               ) -> tuple[np.ndarray, np.ndarray]:
    """Centres and widths of ``n_basis`` transient basis functions on the path from ``(phi0, r0)``.

    Centres sit on the canonical path at the times of :func:`transient_times` (evenly spaced up to ``span``, the
    first ``lead`` spacings before the start). Each width makes a basis function cross its neighbours at height
    ``overlap`` (midway to them), but is narrowed where needed so that its value on the next turn of the spiral
    (one period later) stays below ``delta``.

    Returns:
        ``(centres [M, 2], widths [M])``.
    """
    if n_basis < 1:
        raise ValueError(f"n_transient: expected at least 1 basis function, got {n_basis}")
    if not 0.0 < overlap < 1.0:
        raise ValueError(f"transient_overlap: must lie in (0, 1), got {overlap!r}")
    times = transient_times(span, n_basis, lead)
    phi, r = canonical.state(times, phi0, r0)
    centres = np.stack([r * np.cos(phi), r * np.sin(phi)], axis=1)
    if n_basis > 1:
        gaps = np.linalg.norm(np.diff(centres, axis=0), axis=1)
        spacing = np.empty(n_basis)
        spacing[0], spacing[-1] = gaps[0], gaps[-1]
        spacing[1:-1] = 0.5 * (gaps[1:] + gaps[:-1])
    else:
        spacing = np.array([max(r0 - canonical.mu, 1e-3)])
    widths = np.log(1.0 / overlap) / (0.5 * spacing) ** 2
    next_turn = r - canonical.radius(times + canonical.period / canonical.tempo, r0)
    turn_limit = np.log(1.0 / delta) / np.maximum(np.abs(next_turn), 1e-12) ** 2
    return centres, np.maximum(widths, turn_limit)


def _active_span(gate: np.ndarray) -> slice:
    """The smallest slice along the last (time) axis that holds every non-zero entry of ``gate [..., T]``."""
    active = np.flatnonzero(np.any(gate > 0.0, axis=tuple(range(gate.ndim - 1))))
    return slice(int(active[0]), int(active[-1]) + 1) if active.size else slice(0, 0)


@dataclass(frozen=True)
class BasisSet:
    """All basis functions of a rhythmic DMP: N periodic ones and the transient sets of K transients.

    Attributes:
        periodic_centres: ``[N]`` phases ``c_i``.
        periodic_widths: ``[N]`` widths ``v_i``.
        transient_centres: ``[M, 2]`` phase-plane centres ``q_j`` of all transients, stacked.
        transient_widths: ``[M]`` widths ``vbar_j``.
        transient_sizes: ``(M_1, ..., M_K)`` how many of the stacked transient functions belong to each transient.
        fading: the gates ``g`` and ``a``.
    """

    periodic_centres: np.ndarray
    periodic_widths: np.ndarray
    transient_centres: np.ndarray
    transient_widths: np.ndarray
    transient_sizes: tuple[int, ...]
    fading: Fading

    @property
    def n_periodic(self) -> int:
        return int(self.periodic_centres.size)

    @property
    def n_basis(self) -> int:
        """Total number of basis functions D = N + sum_k M_k."""
        return self.n_periodic + int(self.transient_widths.size)

    def activations(self, phi: np.ndarray, r: np.ndarray) -> np.ndarray:
        """Raw activations ``Psi`` (6) at canonical states: ``phi, r`` of shape ``[..., T]`` -> ``[..., T, D]``.

        Each family is evaluated only over the span of samples where its gate is non-zero (along a path
        r is monotonic: the periodic family is off during most of a long transient, the transient
        family is off on the cycle); outside that span it is exactly 0.
        """
        phi, r = np.broadcast_arrays(np.asarray(phi, dtype=float), np.asarray(r, dtype=float))
        out = np.zeros((*phi.shape, self.n_basis))
        periodic_gate, transient_gate = self.fading.periodic_gate(r), self.fading.transient_gate(r)
        span = _active_span(periodic_gate)
        np.multiply(von_mises(phi[..., span], self.periodic_centres, self.periodic_widths),
                    periodic_gate[..., span, None], out=out[..., span, : self.n_periodic])
        span = _active_span(transient_gate)
        radius, angle = r[..., span, None], phi[..., span, None]
        q = self.transient_centres
        distance_sq = (radius**2 + np.sum(q**2, axis=1)
                       - 2.0 * radius * (np.cos(angle) * q[:, 0] + np.sin(angle) * q[:, 1]))
        np.maximum(distance_sq, 0.0, out=distance_sq)
        distance_sq *= -self.transient_widths           # = -vbar * max(distance^2, 0)
        np.exp(distance_sq, out=distance_sq)
        np.multiply(distance_sq, transient_gate[..., span, None], out=out[..., span, self.n_periodic :])
        return out

    def forcing(self, phi: np.ndarray, r: np.ndarray, weights: np.ndarray) -> np.ndarray:
        """The forcing term (5), ``sum Psi w / (sum Psi + floor)``: ``phi, r [T]`` and ``weights [..., d, D]``
        -> ``[..., T, d]`` (the normalisation is applied to the ``d`` outputs, not the ``D`` activations).
        Evaluated in blocks of ``FORCING_BLOCK`` samples, so memory beyond the output does not grow with T."""
        phi, r = np.broadcast_arrays(np.asarray(phi, dtype=float), np.asarray(r, dtype=float))
        transposed = np.swapaxes(weights, -1, -2)
        blocks = []
        for start in range(0, max(phi.shape[-1], 1), FORCING_BLOCK):
            raw = self.activations(phi[..., start:start + FORCING_BLOCK], r[..., start:start + FORCING_BLOCK])
            block = raw @ transposed
            block /= raw.sum(axis=-1, keepdims=True) + self.fading.floor
            blocks.append(block)
        return blocks[0] if len(blocks) == 1 else np.concatenate(blocks, axis=-2)

    def normalized(self, phi: np.ndarray, r: np.ndarray) -> np.ndarray:
        """Normalised activations ``Psi / (sum Psi + floor)``, ``[..., T, D]``; the forcing term is this @ W."""
        return normalize(self.activations(phi, r), self.fading.floor)
