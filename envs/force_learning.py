"""Force-profile learning (Gams et al. 2010, the paper's [17]): the pressing depth that gives the target force
is learned as a periodic function of the DMP's phase and fed forward on the next periods.

On a tilted or curved surface the depth that holds the target force changes along the wiping pattern, so it
is periodic in the DMP's phase. The admittance law of :class:`~rdmp_gym.envs.controller.ForceAdaptation`
follows it with a lag (about ``1 / (gain * stiffness)``) and leaves a force error every period. Here

    depth(t) = preload + o(t) + h(phi(t)),     h(phi) = sum_i psi_i(phi) w_i / sum_i psi_i

with ``o`` the admittance offset (feedback, unchanged) and ``h`` a second periodic forcing term (von Mises
basis on the phase, like the DMP's periodic family), learned from the force error like an iterative
learning controller: the error measured now is charged to the phase at which the depth was commanded
``delay`` seconds ago (the lag of servo, contact and force filter),

    w += lambda * psibar(phi(t - delay)) * (F_target - F(t)) / stiffness,

with ``lambda`` such that about ``gain`` of a period's error (in depth, ``error / stiffness``) is learned per
period. Its fixed point is zero force error at every phase; the profile feeds the depth forward, so the
error falls period by period.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import uniform_filter1d

from rdmp_gym.basis import periodic_width, von_mises

from .controller import ForceAdaptation, ForceAdaptationSettings

__all__ = ["ForceProfileLearning", "ForceProfileSettings", "period_force_errors"]


@dataclass(frozen=True)
class ForceProfileSettings:
    """The learned periodic depth profile.

    Attributes:
        n_basis: von Mises basis functions over one period.
        overlap: height at which neighbouring basis functions cross.
        gain: share of a period's force error (as depth) learned per period, in (0, 1].
        delay: lag (s) from a depth command to the measured force it causes.
    """

    n_basis: int = 20
    overlap: float = 0.5
    gain: float = 1.0
    delay: float = 0.05

    def __post_init__(self) -> None:
        if isinstance(self.n_basis, bool) or not isinstance(self.n_basis, (int, np.integer)) or self.n_basis < 2:
            raise ValueError(f"n_basis: expected an int >= 2, got {self.n_basis!r}")
        if not 0.0 < self.gain <= 1.0:
            raise ValueError(f"gain: expected a value in (0, 1], got {self.gain!r}")
        if not (np.isfinite(self.delay) and self.delay >= 0.0):
            raise ValueError(f"delay: expected a number >= 0, got {self.delay!r}")
        periodic_width(int(self.n_basis), self.overlap)          # validates overlap


class ForceProfileLearning(ForceAdaptation):
    """Admittance control of the pressing depth plus a feed-forward depth profile learned over the periods.

    Args:
        settings: the admittance law (as :class:`ForceAdaptation`).
        dt: control period (s).
        period: period of the wiping pattern (s).
        phase0: the DMP's phase at the first control step (rad).
        profile: the profile's settings.
    """

    def __init__(self, settings: ForceAdaptationSettings, dt: float, period: float, phase0: float = 0.0,
                 profile: ForceProfileSettings | None = None):
        if not np.isfinite(period) or period <= 0:
            raise ValueError(f"period: expected a finite positive number, got {period!r}")
        self.profile = ForceProfileSettings() if profile is None else profile
        self.period, self.phase0 = float(period), float(phase0)
        n = int(self.profile.n_basis)
        self.centres = 2.0 * np.pi * np.arange(n) / n
        self.widths = np.full(n, periodic_width(n, self.profile.overlap))
        # over one period (``steps`` samples) a constant error e moves each w_i by lambda e sum_t psibar_i(t)
        # = lambda e steps / n, and so h by the same amount; that should be ``gain`` e
        steps = max(round(period / dt), 1)
        self.rate = float(self.profile.gain * n / steps)
        self.delay_steps = round(self.profile.delay / dt)
        super().__init__(settings, dt)

    def reset(self) -> None:
        """Zero the feedback, the force filter, the step counter and the learned profile."""
        super().reset()
        self.weights = np.zeros(int(self.profile.n_basis))
        self.step = 0

    def _basis(self, step: int) -> np.ndarray:
        phase = self.phase0 + 2.0 * np.pi * step * self.dt / self.period
        activations = von_mises(np.array(phase), self.centres, self.widths)
        return activations / activations.sum()

    def feedforward(self) -> float:
        """The learned depth at the current phase (m)."""
        return float(self._basis(self.step) @ self.weights)

    def learn(self, filtered_force: float, engage: float) -> float:
        """One control step of the profile: learn from the filtered force (N) at engagement ``engage`` in
        [0, 1] and return the learned depth (m) to add to the admittance's (called by :meth:`update`, and by
        episode loops that inline the admittance law)."""
        s = self.settings
        if s.enabled and engage > 0.0 and self.step >= self.delay_steps:
            error = (s.target_force - filtered_force) / s.stiffness
            self.weights += self.rate * engage * error * self._basis(self.step - self.delay_steps)
        depth = float(self._basis(self.step) @ self.weights)
        self.step += 1
        return depth

    def update(self, force: float, path_height: float) -> float:
        """Feed one force measurement (N, + = pressing) and return the depth to command (m)."""
        feedback = super().update(force, path_height)
        engage = min(1.0, max(0.0, 1.0 - path_height / self.settings.engage_height))
        return feedback + self.learn(self.force, engage)


def period_force_errors(force: np.ndarray, dt: float, start: float, period: float, target: float,
                        smoothing: float = 0.1) -> np.ndarray:
    """Mean absolute error ``[P]`` (N) of the force ``[T]``, averaged over ``smoothing`` seconds (the contact
    chatter above the control bandwidth removed), in each whole period after time ``start`` (s)."""
    if smoothing > 0.0:
        force = uniform_filter1d(np.asarray(force, dtype=np.float64), max(round(smoothing / dt), 1), mode="nearest")
    first = int(np.ceil(start / dt))
    per = round(period / dt)
    count = (force.size - first) // per
    if count < 1:
        raise ValueError("force: shorter than one period after start")
    chunks = force[first:first + count * per].reshape(count, per)
    return np.mean(np.abs(chunks - target), axis=1)
