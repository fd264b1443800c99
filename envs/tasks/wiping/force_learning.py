"""Force-profile learning (Gams et al. 2010, the paper's [17]): the pressing depth that gives the target force
is learned as a periodic function of the DMP's phase and fed forward on the next periods.

Wherever the depth that holds the target force changes along the wiping pattern (a tilted or curved surface,
the arm's own dynamics along the pattern), it is periodic in the DMP's phase, and the admittance law of
:class:`~rdmp_gym.envs.controller.ForceAdaptation` (an integrator, ``do/dt = k_a (F* - F)``) follows it with a
lag and leaves the same force error every period. Here

    depth(t) = preload + o(t) + h(phi(t)),     h(phi) = sum_i psi_i(phi) w_i / sum_i psi_i

with ``o`` the admittance offset (feedback, unchanged) and ``h`` a second periodic forcing term (von Mises
basis on the phase, like the DMP's periodic family). ``h`` learns the *whole* depth that would have given the
target force (feedback-error learning): the depth commanded ``delay`` seconds ago (the lag of servo, contact
and force filter), less its mean over the last period, plus the depth the error still asks for,

    w += lambda * psibar(phi(t - delay)) * ((o(t - delay) - mean_period(o)) + (F* - F(t)) / stiffness),

with ``lambda`` such that ``gain`` of a period's correction is learned per period. Learning only the error
term (``(F* - F) / stiffness``) does not work under a fast admittance: the integrator removes any slow
feed-forward change (from the feed-forward depth to the force it acts as a high-pass, ``k s / (s + k_a k)``,
about +85 degrees at the wiping frequency for ArmarWipe-v1's gain), so the learned profile fought the
feedback and the error grew. With the feedback's own periodic part in the update the profile takes it over;
the fixed point is zero error with a constant offset. Learning starts once the admittance has acted for a
whole period (the touchdown's transient is not periodic).

The controller measures the wrist force; the contact force differs from it by the hand's and sponge's
dynamics along the pattern, which the learning cannot see (measured by
``benchmarks/bench_force_learning.py``).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.ndimage import uniform_filter1d

from rdmp_gym.dmp.basis import periodic_width, von_mises

from ...controller import ForceAdaptation, ForceAdaptationSettings
from ...robots import ARMAR3

__all__ = ["ForceProfileLearning", "ForceProfileSettings", "curved_table_scene", "period_force_errors",
           "wavy_contact"]


@dataclass(frozen=True)
class ForceProfileSettings:
    """The learned periodic depth profile.

    Attributes:
        n_basis: von Mises basis functions over one period.
        overlap: height at which neighbouring basis functions cross.
        gain: share of a period's correction (as depth) learned per period, in (0, 1] (0.5 and more let the
            error creep up again after 5 periods on ArmarWipe-v1: the model of the loop is not exact).
        delay: lag (s) from a depth command to the measured force it causes.
    """

    n_basis: int = 20
    overlap: float = 0.5
    gain: float = 0.3
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
        # over one period (``steps`` samples) a constant correction c moves each w_i by lambda c sum_t psibar_i(t)
        # = lambda c steps / n, and so h by the same amount; that should be ``gain`` c
        steps = max(round(period / dt), 1)
        self.rate = float(self.profile.gain * n / steps)
        self.delay_steps = round(self.profile.delay / dt)
        if self.delay_steps >= steps:
            raise ValueError(f"profile: the delay ({self.profile.delay} s) must be shorter than the period "
                             f"({period} s)")
        self.period_steps = steps
        super().__init__(settings, dt)

    def reset(self) -> None:
        """Zero the feedback, the force filter, the step counter, the last period's history and the profile."""
        super().reset()
        self.weights = np.zeros(int(self.profile.n_basis))
        self.step = 0
        self.feedback = 0.0                              # the admittance's offset o (m)
        self.history = np.zeros(self.period_steps)       # o over the last period
        self.engaged = np.zeros(self.period_steps)       # the engagement over the last period

    def _basis(self, step: int) -> np.ndarray:
        phase = self.phase0 + 2.0 * np.pi * step * self.dt / self.period
        activations = von_mises(np.array(phase), self.centres, self.widths)
        return activations / activations.sum()

    def feedforward(self) -> float:
        """The learned depth at the current phase (m)."""
        return float(self._basis(self.step) @ self.weights)

    def learn(self, filtered_force: float, engage: float) -> float:
        """One control step of the profile: learn from the filtered force (N) at engagement ``engage`` in
        [0, 1] and return the learned depth (m) to add to the admittance's (called by :meth:`update`)."""
        s = self.settings
        error = s.target_force - filtered_force
        if s.enabled:          # the admittance's offset, as ForceAdaptation.update computes it
            rate = min(s.max_rate, max(-s.max_rate, s.gain * error * engage))
            self.feedback = min(s.max_offset, max(s.min_offset, self.feedback + rate * self.dt))
        size = self.period_steps
        self.history[self.step % size] = self.feedback
        self.engaged[self.step % size] = engage
        if s.enabled and self.step >= size and self.engaged.min() > 0.0:      # in contact for a whole period
            back = self.step - self.delay_steps
            correction = self.history[back % size] - self.history.mean() + error / s.stiffness
            self.weights += self.rate * engage * correction * self._basis(back)
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


def wavy_contact(controller: ForceAdaptation, dt: float, period: float, periods: int, stiffness: float = 1800.0,
                 lag: float = 0.03, waves: tuple[float, float] = (0.003, 0.001)) -> np.ndarray:
    """The contact force ``[periods * period / dt]`` (N) of ``controller`` pressing a curved surface without
    MuJoCo: the surface height varies along the period as ``waves[0] sin(2 pi t / period) + waves[1]
    cos(4 pi t / period + 0.5)`` (m), the commanded depth reaches the tool through a first-order servo lag
    ``lag`` (s), the force is ``stiffness`` times the penetration (0 off the surface) and is measured exactly."""
    steps = round(periods * period / dt)
    t = np.arange(steps) * dt
    surface = waves[0] * np.sin(2.0 * np.pi * t / period) + waves[1] * np.cos(4.0 * np.pi * t / period + 0.5)
    position, force, trace = 0.0, 0.0, np.empty(steps)
    for k in range(steps):
        command = controller.update(force, 0.0)
        position += dt / lag * (command - position)
        force = max(stiffness * (position - surface[k]), 0.0)
        trace[k] = force
    return trace


#: The packaged scene's table top (a box) that :func:`curved_table_scene` replaces.
_TABLE_TOP = 'type="box" size="0.25 0.45 0.02" pos="0.11 0 -0.02"'


def curved_table_scene(directory: str | Path, crown: float = 0.06) -> Path:
    """Write a copy of the packaged hand-merged wiping scene whose table top is curved (for ``gym.make(...,
    xml_file=path)``) into ``directory`` and return its path.

    The box top becomes the upper half of an ellipsoid with the box's half extents (0.25, 0.45 m) and half height
    ``crown`` (m), its highest point at the nominal table height (the table frame's origin is 0.11 m from it
    towards the robot). The controller still plans on the nominal plane, so the depth that holds the force varies
    along the wiping pattern: with ``crown = 0.06`` the default 12 cm patch at the table frame's origin lies 1 to
    17 mm below the plane."""
    if not (np.isfinite(crown) and crown > 0.0):
        raise ValueError(f"crown: expected a finite positive height (m), got {crown!r}")
    source = Path(ARMAR3.legacy_scene)
    text = source.read_text()
    if text.count(_TABLE_TOP) != 1:
        raise RuntimeError(f"{source}: the table top is not the expected box; update curved_table_scene")
    path = Path(directory) / "wipe_curved.xml"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text.replace(_TABLE_TOP, f'type="ellipsoid" size="0.25 0.45 {crown!r}" pos="0.11 0 {-crown!r}"'))
    return path
