"""Follow an external rhythm: an adaptive-frequency oscillator drives the DMP's phase (Righetti, Buchli and
Ijspeert 2006; Petrič, Gams, Ijspeert and Žlajpah 2011).

The oscillator (the adaptive phase oscillator of Righetti et al., as used by Petrič et al.) reads a periodic
input ``u(t)``, normalised online to ``F = (u - m) / (sqrt(2) s)`` (running mean ``m`` and standard deviation
``s`` over about one period), and adapts its own phase and frequency:

    dphi_A/dt   = Omega_A - K F sin(phi_A)
    dOmega_A/dt =         - K_Omega F sin(phi_A)          (K_Omega = K in Righetti et al.)

For a sinusoidal input of phase psi this averages to ``dOmega_A/dt = -K_Omega/2 sin(phi_A - psi)``: the one stable
state is ``Omega_A = dpsi/dt`` and ``phi_A = psi`` (the input's fundamental). Petrič et al. add an adaptive
Fourier series and couple through its error; that leaves the phase offset neutral (the series absorbs any
offset), so here the input itself couples and the offset is defined.

The DMP does not take ``phi_A`` directly (it carries a ripple at twice the input frequency); it runs on a
canonical time ``s`` whose rate follows the oscillator smoothly,

    ds/dt = (Omega_bar + k_phi * wrap(phi_A - phi(s))) / Omega,     phi(s) = phi0 + Omega s,
    dOmega_bar/dt = (Omega_A - Omega_bar) / tau_Omega,

with ``Omega`` the fitted frequency and ``Omega_bar`` the oscillator's frequency low-passed over ``tau_Omega``
(one period by default; the oscillator's frequency ripples at twice the input frequency). Phase and radius
move together along the fitted canonical path, so the start transient and the stop
(:mod:`rdmp_gym.dmp.stopping`, exit and rest in ``s``) keep their shape in space, and the transformation
system (4) is integrated in ``s`` (exact first-order hold, variable step ``ds``): ``dy/dt = (ds/dt) dy/ds``.
"""

from __future__ import annotations

import numpy as np

from ..validation import as_finite_array, check_positive
from .ending import StopPlan, StopRequest
from .start import blend_shift

__all__ = ["AdaptiveFrequencyStepper", "AdaptiveOscillator", "follow_rhythm"]


def _wrap(angle: float) -> float:
    return float(np.angle(np.exp(1j * angle)))


def _first_order_hold(omega: float, h: float, alpha_z: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(Phi [2, 2], B0 [2], B1 [2])`` of the transformation system (4) for a step ``h``, in closed form.

    ``A`` has the double eigenvalue ``lam = -alpha_z Omega / 2``, so with ``N = (A - lam I) h`` (``N^2 = 0``)
    every matrix function is ``f(lam h) I + f'(lam h) N``: ``Phi = e^(A h)``, ``B0 = h (phi1 - phi2) b``,
    ``B1 = h phi2 b`` with ``phi1(x) = (e^x - 1)/x`` and ``phi2(x) = (e^x - 1 - x)/x^2`` (the same step as
    :class:`rdmp_gym.dmp.transformation.TransformationSystem`, without a matrix exponential per step)."""
    lam = -0.5 * alpha_z * omega
    n = (omega * np.array([[0.0, 1.0], [-alpha_z**2 / 4.0, -alpha_z]]) - lam * np.eye(2)) * h
    x = lam * h
    if abs(x) < 1e-3:        # Taylor series where the closed forms cancel
        p1, dp1 = 1.0 + x / 2.0 + x**2 / 6.0, 0.5 + x / 3.0 + x**2 / 8.0
        p2, dp2 = 0.5 + x / 6.0 + x**2 / 24.0, 1.0 / 6.0 + x / 12.0 + x**2 / 40.0
    else:
        ex, em1 = np.exp(x), np.expm1(x)
        p1, dp1 = em1 / x, (x * ex - em1) / x**2
        p2, dp2 = (em1 - x) / x**2, (em1 * x - 2.0 * (em1 - x)) / x**3
    phi = np.exp(x) * (np.eye(2) + n)
    b1 = h * (p2 * np.eye(2) + dp2 * n)[:, 1]
    return phi, h * ((p1 - p2) * np.eye(2) + (dp1 - dp2) * n)[:, 1], b1


class AdaptiveOscillator:
    """The adaptive-frequency phase oscillator, integrated with explicit Euler steps.

    The input is normalised by its mean and standard deviation over the last period (a moving window of
    ``2 pi / Omega_A``, which removes the fundamental and its harmonics from the mean exactly); until one
    period of input has been seen the oscillator runs freely.

    Args:
        omega: initial frequency Omega_A (rad/s).
        phase: initial phase phi_A (rad).
        coupling: K (1/s).
        dt: the sample period of the input (s).
        frequency_coupling: the gain of the frequency equation (1/s; default K, as Righetti et al.).
    """

    def __init__(self, omega: float, phase: float = 0.0, coupling: float = 2.0, dt: float = 2e-3,
                 frequency_coupling: float | None = None) -> None:
        self.omega = check_positive(omega, "omega")
        self.phase = float(as_finite_array(phase, "phase", ndim=0))
        self.coupling = check_positive(coupling, "coupling")
        self.frequency_coupling = (self.coupling if frequency_coupling is None
                                   else check_positive(frequency_coupling, "frequency_coupling"))
        self.dt = check_positive(dt, "dt")
        self._history: list[np.ndarray] = []
        self._capacity = 4 * round(2.0 * np.pi / self.omega / self.dt) + 1

    def normalised(self, u: np.ndarray) -> float:
        """The input's normalised sum ``sum_i F_i`` (0 until one period has been seen), after storing ``u [k]``."""
        self._history.append(u)
        if len(self._history) > self._capacity:
            del self._history[: len(self._history) - self._capacity]
        window = max(round(2.0 * np.pi / self.omega / self.dt), 2)
        if len(self._history) < window:
            return 0.0
        recent = np.array(self._history[-window:])
        mean, deviation = recent.mean(axis=0), recent.std(axis=0)
        live = deviation > 1e-12 * (1.0 + np.abs(mean))
        return float(np.sum((u[live] - mean[live]) / (np.sqrt(2.0) * deviation[live])))

    def step(self, u: np.ndarray) -> tuple[float, float]:
        """Advance by ``dt`` with input ``u [k]``; returns ``(phi_A, Omega_A)``."""
        push = self.normalised(u) * np.sin(self.phase)
        self.phase += self.dt * (self.omega - self.coupling * push)
        self.omega = max(self.omega - self.dt * self.frequency_coupling * push, 1e-6)
        return self.phase, self.omega


class AdaptiveFrequencyStepper:
    """Online rollout of a :class:`rdmp_gym.RhythmicDMP` whose phase and frequency lock onto an input rhythm.

    Args:
        dmp: the DMP (with an ending if :meth:`request_stop` is to be used).
        dt: sample period (s).
        transient: which encoded start.
        coupling: K of the oscillator (1/s).
        phase_gain: ``k_phi`` (1/s), how fast the DMP's phase follows the oscillator's.
        frequency_time: ``tau_Omega`` (s; default one fitted period), the low-pass of the oscillator's frequency.
        frequency_coupling: gain of the oscillator's frequency equation (default ``coupling``).
        oscillator_phase: the oscillator's initial phase (default the DMP's, so a locked input keeps it).
        frequency: the initial frequency (rad/s) of the oscillator and of the rhythm the DMP follows (default the
            fitted one); e.g. a tempo announced before the start.
        start_blend: the smooth start of :meth:`rdmp_gym.RhythmicDMP.rollout` (default; in canonical time).
    """

    BLOCK = 512

    def __init__(self, dmp, dt: float, transient: int = 0, coupling: float = 2.0, phase_gain: float = 1.0,
                 frequency_time: float | None = None, frequency_coupling: float | None = None,
                 oscillator_phase: float | None = None, start_blend: bool = True,
                 frequency: float | None = None) -> None:
        self.dmp, self.dt = dmp, check_positive(dt, "dt")
        self.transient = dmp._check_transient(transient)
        self.start_state = dmp.transients[self.transient]
        self.omega_fit = dmp.canonical.omega
        self.phase_gain = check_positive(phase_gain, "phase_gain")
        initial = self.omega_fit if frequency is None else check_positive(frequency, "frequency")
        self.oscillator = AdaptiveOscillator(initial,
                                             self.start_state.phi0 if oscillator_phase is None else oscillator_phase,
                                             coupling, self.dt, frequency_coupling)
        self.frequency_time = dmp.period if frequency_time is None else check_positive(frequency_time,
                                                                                         "frequency_time")
        self.smoothed_frequency = initial
        self.s, self.time, self.rate = 0.0, 0.0, 1.0
        self._block_index, self._block = -1, np.empty((0, dmp.n_dims))
        self.y = self.start_state.start.copy()
        self.z = self.start_state.start_velocity / self.omega_fit
        self.stop: StopPlan | None = None
        self.start_offsets = None
        if start_blend:
            y_settled, yd_settled = dmp.settled_start(self.transient, 1.0)
            self.start_offsets = (self.start_state.start - y_settled, self.start_state.start_velocity - yd_settled)

    @property
    def phase(self) -> float:
        """The DMP's canonical phase phi(s) (rad, unwrapped)."""
        return self.start_state.phi0 + self.omega_fit * self.s

    @property
    def state(self) -> tuple[np.ndarray, np.ndarray]:
        """Current ``(y [d], yd [d])`` in real time."""
        return self.y.copy(), self.rate * self.omega_fit * self.z

    def _drive_block(self, index: int) -> np.ndarray:
        """``alpha_z beta_z g + f`` ``[BLOCK + 1, d]`` on the canonical-time grid of block ``index`` (spacing dt)."""
        dmp, start = self.dmp, self.start_state
        times = (index * self.BLOCK + np.arange(self.BLOCK + 1)) * self.dt
        phi, r = dmp.canonical.state(times, start.phi0, start.r0)
        if self.stop is None:
            forcing, anchor = dmp.basis.forcing(phi, r, dmp.weights), dmp.anchor[None]
        else:
            tau = times - self.stop.exit_time
            forcing = dmp.ending.forcing(dmp.basis, phi, r, tau, self.stop.rotation, dmp.weights, dmp.ending.weights)
            anchor = dmp.anchor + dmp.ending.anchor_blend(tau)[:, None] * (self.stop.goal[0] - dmp.anchor)
        if self.start_offsets is not None:
            anchor = anchor + blend_shift(times, np.array([start.length]), self.start_offsets[0][None],
                                           self.start_offsets[1][None], self.omega_fit, dmp.alpha_z)[0]
        return dmp.alpha_z * dmp.alpha_z / 4.0 * anchor + dmp.amplitude * forcing

    def _drive(self, s: float) -> np.ndarray:
        """The drive at canonical time ``s`` ``[d]``, interpolated linearly on the grid (spacing dt)."""
        position = s / self.dt
        index = min(int(position // self.BLOCK), int(position) // self.BLOCK)
        if index != self._block_index:
            self._block, self._block_index = self._drive_block(index), index
        offset = position - index * self.BLOCK
        low = min(int(offset), self.BLOCK - 1)
        weight = offset - low
        return (1.0 - weight) * self._block[low] + weight * self._block[low + 1]

    def request_stop(self, exit_phase: float | None = None, goal: np.ndarray | None = None) -> float:
        """As :meth:`rdmp_gym.DMPStepper.request_stop`, in canonical time; returns the exit's canonical time ``s``."""
        if self.stop is not None:
            raise ValueError("request_stop: a stop has already been requested")
        plan = self.dmp._stop_plan(StopRequest(self.s, exit_phase, goal), self.start_state, 1.0, self.dmp.anchor[None],
                                   self.dmp.amplitude[None])
        self.stop = plan
        self._block_index = -1
        return plan.exit_time

    def step(self, u: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        """Advance by ``dt`` reading the input sample ``u`` (a number or ``[k]``); returns ``(y [d], yd [d])``."""
        u = np.atleast_1d(as_finite_array(u, "u", ndim=(0, 1)))
        phase_error = _wrap(self.oscillator.phase - self.phase)
        self.rate = max(self.smoothed_frequency + self.phase_gain * phase_error, 0.0) / self.omega_fit
        ds = self.rate * self.dt
        if ds > 0.0:
            phi, b0, b1 = _first_order_hold(self.omega_fit, ds, self.dmp.alpha_z)
            u_now = self.omega_fit * self._drive(self.s)
            u_next = self.omega_fit * self._drive(self.s + ds)
            state = phi @ np.stack([self.y, self.z]) + b0[:, None] * u_now + b1[:, None] * u_next
            self.y, self.z = state[0], state[1]
            self.s += ds
        _, omega_a = self.oscillator.step(u)
        self.smoothed_frequency += min(self.dt / self.frequency_time, 1.0) * (omega_a - self.smoothed_frequency)
        self.time += self.dt
        return self.state

    @property
    def frequency(self) -> float:
        """The oscillator's adapted frequency Omega_A (rad/s)."""
        return self.oscillator.omega


def follow_rhythm(dmp, u: np.ndarray, dt: float, *, stop_at: float | None = None, **stepper_kwargs
                  ) -> dict[str, np.ndarray]:
    """Run an :class:`AdaptiveFrequencyStepper` over an input recording.

    Args:
        dmp: the DMP.
        u: ``[T]`` or ``[T, k]`` input samples at spacing ``dt``.
        dt: sample period (s).
        stop_at: request the stop at this time (s).
        stepper_kwargs: passed to :class:`AdaptiveFrequencyStepper`.
    Returns:
        ``y``, ``yd`` ``[T, d]`` (the state after each sample), ``phase`` ``[T]`` (the DMP's canonical phase,
        unwrapped), ``frequency`` ``[T]`` (the smoothed frequency the DMP follows, rad/s) and ``oscillator``
        ``[T]`` (the oscillator's raw frequency).
    """
    u = as_finite_array(u, "u", ndim=(1, 2))
    stepper = AdaptiveFrequencyStepper(dmp, dt, **stepper_kwargs)
    n = u.shape[0]
    out = {"y": np.empty((n, dmp.n_dims)), "yd": np.empty((n, dmp.n_dims)), "phase": np.empty(n),
           "frequency": np.empty(n), "oscillator": np.empty(n)}
    stop_step = None if stop_at is None else round(float(stop_at) / dt)
    for i in range(n):
        if i == stop_step:
            stepper.request_stop()
        out["y"][i], out["yd"][i] = stepper.step(u[i])
        out["phase"][i], out["frequency"][i], out["oscillator"][i] = (stepper.phase, stepper.smoothed_frequency,
                                                                      stepper.frequency)
    return out
