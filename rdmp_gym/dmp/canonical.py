"""The 2-D limit-cycle canonical system of Ernesti et al. (2012), eq. (3), and ``init_T`` (III-D).

    dphi/dt = tempo * Omega
    dr/dt   = tempo * eta * (mu**alpha - r**alpha) * r**beta

The radial equation is scalar and autonomous, so its solution is a time shift of one reference
solution. We tabulate, once per set of constants, the time the system needs to travel along that
solution, using the variable ``x = log|r - mu|`` in which the travel time is smooth and bounded:

    C(x) = integral_{x_lo}^{x} |r - mu| / |dr/dt| dx'          (seconds of unit-tempo time)

``C`` is integrated with 5-point Gauss-Legendre quadrature on a fine grid and inverted with a cubic
spline plus one Newton step, so ``r(t)`` costs two spline evaluations per sample and matches a
tightly integrated reference to about 1e-10 (see ``tests/test_canonical.py``). Below ``x_lo`` (r
within 1e-12 mu of mu) the dynamics are linear and the table is extended exactly by the
exponential ``|r - mu| ~ exp(-lambda t)``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy.interpolate import CubicSpline

from ..validation import as_finite_array, check_positive

__all__ = ["CanonicalSystem"]

_X_LOW = np.log(1e-12)          # log of the smallest tabulated |r - mu| / mu
_X_HIGH_ABOVE = np.log(1e6)     # r up to about 1e6 mu
_R_MIN_BELOW = 1e-9             # smallest r / mu tabulated below the limit cycle
_GRID_STEP = 2e-3
_BLOCK_SAMPLES = 8192           # samples per block in CanonicalSystem.radius


@dataclass(frozen=True)
class _Branch:
    """Travel-time table for one side of the limit cycle (``sign`` = +1 above, -1 below)."""

    sign: int
    x_grid: np.ndarray       # [G] log|r - mu|
    c_grid: np.ndarray       # [G] travel time from x_lo, increasing
    c_of_x: CubicSpline
    x_of_c: CubicSpline
    rate_low: float          # dx/dC at x_lo (the linearised decay rate, lambda)


class _TravelTime:
    """Travel-time tables of the radial equation for fixed constants (mu, eta, alpha, beta)."""

    def __init__(self, mu: float, eta: float, alpha: float, beta: float) -> None:
        self.mu, self.eta, self.alpha, self.beta = mu, eta, alpha, beta
        x_low = _X_LOW + np.log(mu)
        self.above = self._build(+1, x_low, _X_HIGH_ABOVE + np.log(mu))
        self.below = self._build(-1, x_low, np.log(mu * (1.0 - _R_MIN_BELOW)))

    def speed(self, r: np.ndarray) -> np.ndarray:
        """|dr/dt| at unit tempo, ``r`` any shape."""
        return np.abs(self.eta * (self.mu**self.alpha - r**self.alpha) * r**self.beta)

    def _dt_dx(self, x: np.ndarray, sign: int) -> np.ndarray:
        distance = np.exp(x)
        return distance / self.speed(self.mu + sign * distance)

    def _build(self, sign: int, x_low: float, x_high: float) -> _Branch:
        n = int(np.ceil((x_high - x_low) / _GRID_STEP))
        x_grid = np.linspace(x_low, x_high, n + 1)
        nodes, weights = np.polynomial.legendre.leggauss(5)
        half = 0.5 * np.diff(x_grid)
        mid = 0.5 * (x_grid[1:] + x_grid[:-1])
        samples = self._dt_dx(mid[:, None] + half[:, None] * nodes[None, :], sign)
        pieces = half * (samples @ weights)
        c_grid = np.concatenate([[0.0], np.cumsum(pieces)])
        rate_low = 1.0 / float(self._dt_dx(np.array(x_low), sign))
        return _Branch(sign, x_grid, c_grid, CubicSpline(x_grid, c_grid),
                       CubicSpline(c_grid, x_grid), rate_low)

    def branch(self, r: np.ndarray) -> np.ndarray:
        """+1 where r > mu, -1 where r < mu, 0 on the limit cycle."""
        return np.sign(r - self.mu).astype(int)

    def travel(self, r: np.ndarray) -> np.ndarray:
        """Unit-tempo travel time C from r down (or up) to the table's inner edge; ``inf`` on the cycle."""
        out = np.full(r.shape, np.inf)
        for branch in (self.above, self.below):
            mask = np.sign(r - self.mu) == branch.sign
            if np.any(mask):
                out[mask] = self._c_of_x(branch, np.log(np.abs(r[mask] - self.mu)))
        return out

    def _c_of_x(self, branch: _Branch, x: np.ndarray) -> np.ndarray:
        inside = x >= branch.x_grid[0]
        return np.where(inside, branch.c_of_x(np.maximum(x, branch.x_grid[0])),
                        (x - branch.x_grid[0]) / branch.rate_low)

    def radius_after(self, c: np.ndarray, sign: np.ndarray) -> np.ndarray:
        """Radius whose travel time is ``c`` on the branch ``sign`` (+1/-1); ``mu`` where sign == 0."""
        r = np.full(c.shape, self.mu)
        for branch in (self.above, self.below):
            mask = sign == branch.sign
            if not np.any(mask):
                continue
            whole = bool(np.all(mask))                      # one branch only: no gather and scatter
            target = c.reshape(-1) if whole else c[mask]
            x = self._x_of_c(branch, target)
            # One Newton step on C(x) = target removes the inverse spline's error.
            inside = target > 0.0
            if np.any(inside):
                every = bool(np.all(inside))
                xi = x if every else x[inside]
                value, slope = _value_and_slope(branch, xi)
                xi = xi - (value - (target if every else target[inside])) * (1.0 / slope)
                if every:
                    x = xi
                else:
                    x[inside] = xi
            np.exp(x, out=x)
            x *= branch.sign
            x += self.mu
            if whole:
                r = x.reshape(c.shape)
            else:
                r[mask] = x
        return r

    def _x_of_c(self, branch: _Branch, c: np.ndarray) -> np.ndarray:
        if np.any(c > branch.c_grid[-1]):
            raise ValueError("r0: the canonical state lies outside the tabulated range "
                             f"(travel time {c.max():.3g} s > {branch.c_grid[-1]:.3g} s)")
        x = branch.x_grid[0] + c * branch.rate_low          # linear beyond the table's inner edge
        inside = c >= 0.0
        if np.any(inside):                                  # the spline only where it is needed
            x[inside] = branch.x_of_c(c[inside])
        return x

    def max_travel(self, sign: int) -> float:
        """The longest tabulated travel time on a branch (s, unit tempo)."""
        return float((self.above if sign > 0 else self.below).c_grid[-1])


def _value_and_slope(branch: _Branch, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(branch.c_of_x(x), branch.c_of_x(x, 1))`` with one interval look-up for both: the grid is uniform, so
    the interval is computed rather than searched (the same interval, and so the same numbers, as scipy's
    ``PPoly`` evaluation, which sums the power form in the same order; extrapolation from the end intervals)."""
    knots, coefficients = branch.x_grid, branch.c_of_x.c                  # [G], [4, G - 1]
    last = knots.size - 2
    index = np.clip(np.floor((x - knots[0]) * (last / (knots[-1] - knots[0]))), 0, last).astype(np.intp)
    index -= (index > 0) & (x < knots[index])                            # rounding of the computed interval
    index += (index < last) & (x >= knots[np.minimum(index + 1, last + 1)])
    s = x - knots[index]
    c0, c1, c2, c3 = (coefficients[k, index] for k in range(4))
    square = s * s
    value = c3 + c2 * s + c1 * square + c0 * (square * s)
    slope = c2 + c1 * s * 2.0 + c0 * square * 3.0
    return value, slope


@lru_cache(maxsize=8)
def _travel_time(mu: float, eta: float, alpha: float, beta: float) -> _TravelTime:
    with np.errstate(all="ignore"):
        try:
            return _TravelTime(mu, eta, alpha, beta)
        except ValueError as error:     # the tables overflow: travel times beyond float64
            raise ValueError(f"mu, eta, alpha, beta: the radial dynamics with ({mu:g}, {eta:g}, {alpha:g}, "
                             f"{beta:g}) are too slow or too fast to tabulate ({error})") from error


@dataclass(frozen=True)
class CanonicalSystem:
    """The limit-cycle oscillator (3) shared by all degrees of freedom.

    Args:
        period: period of the rhythmic pattern in seconds (``Omega = 2 pi / period``).
        mu: radius of the limit cycle.
        eta, alpha, beta: convergence constants of the radial equation (the paper's defaults).
        tempo: time scaling of both phase and radius dynamics (0.5 = half speed).
    """

    period: float
    mu: float = 1.0
    eta: float = 35.0
    alpha: float = 1.0 / 6.0
    beta: float = 1.0 / 1000.0
    tempo: float = 1.0

    def __post_init__(self) -> None:
        for name in ("period", "mu", "eta", "alpha", "beta", "tempo"):
            object.__setattr__(self, name, check_positive(getattr(self, name), name))

    @property
    def omega(self) -> float:
        """Angular velocity ``Omega = 2 pi / period`` (rad/s at unit tempo)."""
        return 2.0 * np.pi / self.period

    @property
    def _table(self) -> _TravelTime:
        return _travel_time(self.mu, self.eta, self.alpha, self.beta)

    def radial_rate(self, r: np.ndarray) -> np.ndarray:
        """dr/dt of (3b) including tempo, ``r`` any shape (> 0)."""
        r = np.asarray(r, dtype=float)
        return self.tempo * self.eta * (self.mu**self.alpha - r**self.alpha) * r**self.beta

    def _check_r0(self, r0: np.ndarray) -> np.ndarray:
        r0 = as_finite_array(r0, "r0")
        if np.any(r0 <= self.mu * _R_MIN_BELOW):
            raise ValueError(f"r0: the initial radius must be > {self.mu * _R_MIN_BELOW:g}, "
                             f"got {r0.min()!r}")
        if np.any(r0 > self.mu * np.exp(_X_HIGH_ABOVE)):
            raise ValueError(f"r0: the initial radius must be < {self.mu * np.exp(_X_HIGH_ABOVE):g}, "
                             f"got {r0.max()!r}")
        return r0

    def radius(self, t: np.ndarray, r0: float | np.ndarray) -> np.ndarray:
        """r(t) from r(0) = r0.

        Args:
            t: times ``[T]`` (s, >= 0 is the future; negative times run backwards within the table).
            r0: a scalar or ``[B]`` initial radii (> 0).
        Returns:
            ``[T]`` for a scalar ``r0``, ``[B, T]`` otherwise.
        """
        t = as_finite_array(t, "t", ndim=1)
        r0 = self._check_r0(r0)
        table = self._table
        starts, signs = table.travel(r0.reshape(-1)), table.branch(r0.reshape(-1))          # [B] each
        elapsed = self.tempo * t
        out = np.empty((starts.size, t.size))
        rows = max(1, _BLOCK_SAMPLES // max(t.size, 1))  # a few paths at a time: small temporaries, in cache
        for first in range(0, starts.size, rows):
            block = slice(first, first + rows)
            sign = np.broadcast_to(signs[block, None], out[block].shape)
            travel = np.where(sign == 0, 0.0, starts[block, None] - elapsed)   # sign 0 (on the cycle): r = mu
            out[block] = table.radius_after(travel, sign)
        return out.reshape(r0.shape + t.shape)

    def phase(self, t: np.ndarray, phi0: float | np.ndarray) -> np.ndarray:
        """phi(t) = phi0 + tempo * Omega * t, ``[T]`` or ``[B, T]`` for ``phi0`` of shape ``[B]``."""
        t = as_finite_array(t, "t", ndim=1)
        phi0 = as_finite_array(phi0, "phi0")
        return phi0[..., None] + self.tempo * self.omega * t if phi0.ndim else phi0 + self.tempo * self.omega * t

    def state(self, t: np.ndarray, phi0: float | np.ndarray, r0: float | np.ndarray
              ) -> tuple[np.ndarray, np.ndarray]:
        """``(phi(t), r(t))``, each ``[T]`` (scalar initial conditions) or ``[B, T]``."""
        return self.phase(t, phi0), self.radius(t, r0)

    def time_between(self, r_from: float, r_to: float) -> float:
        """Time (s, at this tempo) the system needs to go from ``r_from`` to ``r_to`` on the same side of mu."""
        r_from_a, r_to_a = self._check_r0(np.array([r_from, r_to]))
        table = self._table
        if np.sign(r_from_a - self.mu) != np.sign(r_to_a - self.mu) or r_to_a == self.mu:
            raise ValueError("r_to: must lie strictly on the same side of mu as r_from")
        c_from, c_to = table.travel(np.array([r_from_a, r_to_a]))
        if c_to > c_from:
            raise ValueError("r_to: the system moves towards mu, so r_to must lie between r_from and mu")
        return float(c_from - c_to) / self.tempo

    def init_T(self, transient_length: float, phi_end: float, r_end: float) -> tuple[float, float]:
        """The unique ``(phi0, r0)`` from which the system reaches ``(phi_end, r_end)`` after ``transient_length``.

        ``phi0`` is wrapped into [0, 2 pi). ``r_end`` must differ from mu (the cycle is reached only asymptotically).
        """
        transient_length = check_positive(transient_length, "transient_length")
        phi_end = float(as_finite_array(phi_end, "phi_end", ndim=0))
        r_end = float(self._check_r0(r_end))
        if r_end == self.mu:
            raise ValueError("r_end: must differ from mu; the limit cycle is reached only as t -> inf")
        table = self._table
        sign = 1 if r_end > self.mu else -1
        target = float(table.travel(np.array([r_end]))[0]) + self.tempo * transient_length
        if target > table.max_travel(sign):
            limit = (table.max_travel(sign) - float(table.travel(np.array([r_end]))[0])) / self.tempo
            raise ValueError(f"transient_length: {transient_length:g} s is too long; the system reaches "
                             f"r_end = {r_end:g} from at most {limit:.4g} s away")
        r0 = float(table.radius_after(np.array([target]), np.array([sign]))[0])
        phi0 = float(np.mod(phi_end - self.tempo * self.omega * transient_length, 2.0 * np.pi))
        return phi0, r0
