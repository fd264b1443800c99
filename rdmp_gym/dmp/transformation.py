"""The transformation system (4), integrated exactly for piecewise-linear forcing.

    dz/dt = Omega * (alpha_z * (beta_z * (g - y) - z) + f(t) + c(t))
    dy/dt = Omega * z

For a fixed canonical path the system is linear and time-invariant in ``(y, z)`` with a known input
``u = Omega (alpha_z beta_z g + f + c)``. Holding ``u`` linear between samples (first-order hold) the
step from ``t_k`` to ``t_k + h`` is exact:

    x_{k+1} = Phi x_k + B0 u_k + B1 u_{k+1},       Phi = exp(A h)

This one discretisation serves both execution paths: :meth:`TransformationSystem.step` applies it
one sample at a time (so a coupling term can react to feedback), and
:meth:`TransformationSystem.rollout` applies the same recurrence to whole batches at once as an
IIR filter (``scipy.signal.lfilter``) plus the closed-form free response. Both give the same numbers
to round-off, are unconditionally stable and have no integration error beyond the input hold, which
is why we use it rather than Euler or RK4. Fitting inverts the continuous equation (10) directly.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np
from scipy.linalg import expm
from scipy.signal import lfilter

from ..validation import check_positive

__all__ = ["FREE_RESPONSE_FLOOR", "TransformationSystem", "cached_system"]

FREE_RESPONSE_FLOOR = 1e-17
"""Relative size below which the decaying response to the initial state is taken as 0."""


@dataclass(frozen=True)
class TransformationSystem:
    """Critically damped spring (4) shared in form by every degree of freedom.

    Args:
        omega: angular velocity Omega (rad/s; includes tempo).
        dt: sample period h of the discretisation (s).
        alpha_z: damping gain; ``beta_z = alpha_z / 4`` gives critical damping.
    """

    omega: float
    dt: float
    alpha_z: float = 25.0

    def __post_init__(self) -> None:
        check_positive(self.omega, "omega")
        check_positive(self.dt, "dt")
        check_positive(self.alpha_z, "alpha_z")

    @property
    def beta_z(self) -> float:
        return self.alpha_z / 4.0

    @property
    def system_matrix(self) -> np.ndarray:
        """``A`` of ``dx/dt = A x + b u`` for ``x = (y, z)``; shape ``[2, 2]``."""
        return self.omega * np.array([[0.0, 1.0], [-self.alpha_z * self.beta_z, -self.alpha_z]])

    @cached_property
    def _discrete(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(Phi [2,2], B0 [2], B1 [2])`` from one 4x4 matrix exponential (first-order hold)."""
        h = self.dt
        augmented = np.zeros((4, 4))
        augmented[:2, :2] = self.system_matrix * h
        augmented[1, 2] = h                  # b = (0, 1): the input drives z
        augmented[2, 3] = 1.0                # ramp of the input over the step
        block = expm(augmented)
        phi, gamma0, gamma1 = block[:2, :2], block[:2, 2], block[:2, 3]
        return phi, gamma0 - gamma1, gamma1

    @cached_property
    def _filters(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """IIR coefficients ``(b_y [3], b_z [3], a [3])`` from input ``u`` to outputs ``y`` and ``z``."""
        phi, b0, b1 = self._discrete
        # xi_k = x_k - B1 u_k evolves as xi_{k+1} = Phi xi_k + (Phi B1 + B0) u_k, output x_k = xi_k + B1 u_k.
        b_xi = phi @ b1 + b0
        denominator = np.array([1.0, -np.trace(phi), np.linalg.det(phi)])
        adjugate = np.array([[phi[1, 1], -phi[0, 1]], [-phi[1, 0], phi[0, 0]]])
        numerators = []
        for output in np.eye(2):
            # c (zI - Phi)^-1 b = (z c.b - c.adj(Phi).b) / det(zI - Phi), plus the direct term c.B1
            strictly_proper = np.array([0.0, output @ b_xi, -(output @ adjugate @ b_xi)])
            numerators.append(strictly_proper + (output @ b1) * denominator)
        return numerators[0], numerators[1], denominator

    def input(self, anchor: np.ndarray, forcing: np.ndarray, out: np.ndarray | None = None,
              scratch: bool = False) -> np.ndarray:
        """Input ``u = Omega (alpha_z beta_z g + f)`` for ``forcing [..., T, d]`` and a constant anchor
        ``[..., d]`` or a moving one ``[..., T, d]``; written into ``out`` if given (it may be ``forcing``).
        With ``scratch`` a moving anchor is overwritten instead of copied (no ``[..., T, d]`` temporary)."""
        anchor = anchor if anchor.ndim == forcing.ndim else anchor[..., None, :]
        in_place = scratch and anchor.shape == forcing.shape
        scaled = np.multiply(anchor, self.alpha_z * self.beta_z, out=anchor if in_place else None)
        u = np.add(scaled, forcing, out=out)
        u *= self.omega
        return u

    def free_response(self, times: np.ndarray, state: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``exp(A t) x0`` for ``times [T]`` and ``state [..., 2, d]``, as ``(y, z)`` each ``[..., T, d]``.

        ``A`` has the double eigenvalue ``lam = -alpha_z Omega / 2``, so ``exp(A t) = exp(lam t) (I + (A - lam I) t)``.
        It is evaluated while ``exp(lam t) (1 + |lam| t)`` exceeds ``FREE_RESPONSE_FLOOR`` and is 0 after
        (there it is below the float64 resolution of the initial state it decays from).
        """
        responses = []
        for live in self._live_free_response(times, state, (0, 1)):
            response = np.zeros((*state.shape[:-2], times.size, state.shape[-1]))
            response[..., :live.shape[-2], :] = live
            responses.append(response)
        return responses[0], responses[1]

    def _live_free_response(self, times: np.ndarray, state: np.ndarray, rows: tuple[int, ...]
                            ) -> tuple[np.ndarray, ...]:
        """:meth:`free_response` up to the sample from which it is 0, for the state rows ``rows`` (0: y, 1: z):
        one ``[..., L, d]`` array per row, L <= T."""
        lam = -0.5 * self.alpha_z * self.omega
        slope = (self.system_matrix - lam * np.eye(2)) @ state                    # [..., 2, d]
        decay = np.exp(lam * times)
        live = int(np.count_nonzero(decay * (1.0 - lam * times) > FREE_RESPONSE_FLOOR))   # times increase
        decay, t = decay[:live, None], times[:live, None]
        return tuple(decay * (state[..., row, None, :] + t * slope[..., row, None, :]) for row in rows)

    def rollout(self, u: np.ndarray, y0: np.ndarray, z0: np.ndarray, velocity: bool = True
                ) -> tuple[np.ndarray, np.ndarray | None]:
        """Integrate a whole input sequence.

        Args:
            u: input samples ``[..., T, d]`` at spacing ``dt``.
            y0, z0: initial position and scaled velocity ``z = ydot / Omega``, ``[..., d]``.
            velocity: also compute ``z`` (``False``: ``z`` is ``None``; ``y`` is the same).
        Returns:
            ``(y, z)`` each ``[..., T, d]``.
        """
        b_y, b_z, a = self._filters
        _, _, b1 = self._discrete
        times = np.arange(u.shape[-2]) * self.dt
        xi0 = np.stack([y0, z0], axis=-2) - b1[:, None] * u[..., 0, None, :]
        batch = np.broadcast_shapes(u.shape[:-2], xi0.shape[:-2])
        outputs = []
        rows = (0, 1) if velocity else (0,)
        for numerator, free in zip((b_y, b_z), self._live_free_response(times, xi0, rows), strict=False):
            output = lfilter(numerator, a, u, axis=-2)                          # the filter runs along the time axis
            if batch != output.shape[:-2]:      # initial states for more rollouts than inputs
                output = np.broadcast_to(output, (*batch, *output.shape[-2:])).copy()
            output[..., :free.shape[-2], :] += free                             # in place: no [..., T, d] temporaries
            outputs.append(output)
        return outputs[0], outputs[1] if velocity else None

    def step(self, y: np.ndarray, z: np.ndarray, u_now: np.ndarray, u_next: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray]:
        """Advance ``(y, z)`` (each ``[d]``) by one sample with the input ramping from ``u_now`` to ``u_next``."""
        phi, b0, b1 = self._discrete
        state = phi @ np.stack([y, z]) + b0[:, None] * u_now + b1[:, None] * u_next
        return state[0], state[1]


@lru_cache(maxsize=64)
def cached_system(omega: float, dt: float, alpha_z: float) -> TransformationSystem:
    """The :class:`TransformationSystem` of these constants, built once (its discretisation costs a matrix
    exponential)."""
    return TransformationSystem(omega, dt, alpha_z)
