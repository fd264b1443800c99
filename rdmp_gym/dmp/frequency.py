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

The canonical time does not depend on what drives the transformation system (the forcing weights, the amplitude,
the ending's weights and goal): :class:`CanonicalSchedule` records a run's canonical time once, and the
transformation system of other parameters follows it, bit for bit as the stepper would, at the cost of the drive
and one 2x2 update per step.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..validation import as_finite_array, check_positive
from .ending import StopPlan, StopRequest
from .start import blend_shift

__all__ = ["AdaptiveFrequencyStepper", "AdaptiveOscillator", "CanonicalSchedule", "Retunes", "follow_rhythm"]


#: the 2x2 identity (read-only)
_IDENTITY = np.eye(2)
_IDENTITY.flags.writeable = False


def _wrap(angle: float) -> float:
    return float(np.angle(np.exp(1j * angle)))


def _first_order_hold(omega: float, h: float, alpha_z: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(Phi [2, 2], B0 [2], B1 [2])`` of the transformation system (4) for a step ``h``, in closed form.

    ``A`` has the double eigenvalue ``lam = -alpha_z Omega / 2``, so with ``N = (A - lam I) h`` (``N^2 = 0``)
    every matrix function is ``f(lam h) I + f'(lam h) N``: ``Phi = e^(A h)``, ``B0 = h (phi1 - phi2) b``,
    ``B1 = h phi2 b`` with ``phi1(x) = (e^x - 1)/x`` and ``phi2(x) = (e^x - 1 - x)/x^2`` (the same step as
    :class:`rdmp_gym.dmp.transformation.TransformationSystem`, without a matrix exponential per step)."""
    lam = -0.5 * alpha_z * omega
    n = (omega * np.array([[0.0, 1.0], [-alpha_z**2 / 4.0, -alpha_z]]) - lam * _IDENTITY) * h
    x = lam * h
    if abs(x) < 1e-3:        # Taylor series where the closed forms cancel
        p1, dp1 = 1.0 + x / 2.0 + x**2 / 6.0, 0.5 + x / 3.0 + x**2 / 8.0
        p2, dp2 = 0.5 + x / 6.0 + x**2 / 24.0, 1.0 / 6.0 + x / 12.0 + x**2 / 40.0
    else:
        ex, em1 = np.exp(x), np.expm1(x)
        p1, dp1 = em1 / x, (x * ex - em1) / x**2
        p2, dp2 = (em1 - x) / x**2, (em1 * x - 2.0 * (em1 - x)) / x**3
    phi = np.exp(x) * (_IDENTITY + n)
    b1 = h * (p2 * _IDENTITY + dp2 * n)[:, 1]
    return phi, h * ((p1 - p2) * _IDENTITY + (dp1 - dp2) * n)[:, 1], b1


def _hold_inputs(b0: np.ndarray, b1: np.ndarray, u_now: np.ndarray, u_next: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray]:
    """The input terms ``(B0 u_now, B1 u_next)`` ``[..., 2, d]`` of steps whose first-order holds have ``B0``, ``B1``
    ``[..., 2]`` (:func:`_first_order_hold`), driven by ``u_now``, ``u_next`` ``[..., d]`` (the drive times Omega at
    the steps' starts and ends)."""
    return b0[..., :, None] * u_now[..., None, :], b1[..., :, None] * u_next[..., None, :]


def _hold_update(phi: np.ndarray, state: np.ndarray, inputs: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """One step of the transformation system (4): the state ``[y, z]`` ``[2, d]`` after a step of hold matrix
    ``phi [2, 2]`` and input terms ``inputs`` (:func:`_hold_inputs`, ``[2, d]`` each)."""
    return phi @ state + inputs[0] + inputs[1]


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
        self._capacity = 4 * round(2.0 * np.pi / self.omega / self.dt) + 1
        #: the inputs seen, oldest first, in rows ``[:_used]`` of a buffer of twice the capacity (the last
        #: ``_capacity`` rows are the history; the buffer is allocated at the first input)
        self._history, self._used = np.empty((0, 0)), 0

    def _store(self, u: np.ndarray) -> int:
        """Append ``u [k]`` to the history; returns how many inputs the history holds (at most the capacity)."""
        if not len(self._history):                         # the first input
            self._history = np.empty((2 * self._capacity, u.size))
        if u.shape != self._history.shape[1:]:
            raise ValueError(f"u: expected {self._history.shape[1]} values, as in the earlier inputs, got {u.size}")
        if self._used == len(self._history):              # keep the newest capacity - 1 rows, at the front
            keep = self._capacity - 1
            self._history[:keep] = self._history[self._used - keep: self._used]
            self._used = keep
        self._history[self._used] = u
        self._used += 1
        return min(self._used, self._capacity)

    def normalised(self, u: np.ndarray) -> float:
        """The input's normalised sum ``sum_i F_i`` (0 until one period has been seen), after storing ``u [k]``."""
        held = self._store(u)
        window = max(round(2.0 * np.pi / self.omega / self.dt), 2)
        if held < window:
            return 0.0
        recent = self._history[self._used - window: self._used]
        mean = recent.sum(axis=0) / window
        deviation = np.sqrt(np.square(recent - mean).sum(axis=0) / window)     # recent.std(axis=0), leaner
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
        self._blocks: dict[int, np.ndarray] = {}
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

    def _drive(self, s: np.ndarray) -> np.ndarray:
        """The drive at canonical times ``s [N]`` ``[N, d]``, interpolated linearly on the grid (spacing dt) of the
        blocks of :meth:`_drive_block` (each computed once, and again after a stop request)."""
        position = s / self.dt
        index = np.minimum(position // self.BLOCK, np.trunc(position) // self.BLOCK).astype(int)
        offset = position - index * self.BLOCK
        low = np.minimum(offset.astype(int), self.BLOCK - 1)
        weight = offset - low
        drive = np.empty((s.size, self.dmp.n_dims))
        for block_index in np.unique(index).tolist():
            block = self._blocks.get(block_index)
            if block is None:
                block = self._blocks[block_index] = self._drive_block(block_index)
            rows = np.flatnonzero(index == block_index)
            share = weight[rows, None]                      # of the grid sample after s
            drive[rows] = (1.0 - share) * block[low[rows]] + share * block[low[rows] + 1]
        return drive

    def _set_stop(self, s: float, exit_phase: float | None = None, goal: np.ndarray | None = None) -> None:
        """Plan the stop requested at canonical time ``s``; the drive from now on includes it."""
        self.stop = self.dmp._stop_plan(StopRequest(s, exit_phase, goal), self.start_state, 1.0,
                                        self.dmp.anchor[None], self.dmp.amplitude[None])
        self._blocks.clear()

    def request_stop(self, exit_phase: float | None = None, goal: np.ndarray | None = None) -> float:
        """As :meth:`rdmp_gym.DMPStepper.request_stop`, in canonical time; returns the exit's canonical time ``s``."""
        if self.stop is not None:
            raise ValueError("request_stop: a stop has already been requested")
        self._set_stop(self.s, exit_phase, goal)
        return self.stop.exit_time

    def _advance_canonical(self, u: np.ndarray) -> float:
        """Advance the canonical time, the oscillator (reading the input sample ``u [k]``) and the smoothed frequency
        by ``dt``; returns the step ``ds`` of the canonical time (>= 0). The transformation system plays no part."""
        phase_error = _wrap(self.oscillator.phase - self.phase)
        self.rate = max(self.smoothed_frequency + self.phase_gain * phase_error, 0.0) / self.omega_fit
        ds = self.rate * self.dt
        self.s += ds
        _, omega_a = self.oscillator.step(u)
        self.smoothed_frequency += min(self.dt / self.frequency_time, 1.0) * (omega_a - self.smoothed_frequency)
        self.time += self.dt
        return ds

    def step(self, u: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        """Advance by ``dt`` reading the input sample ``u`` (a number or ``[k]``); returns ``(y [d], yd [d])``."""
        u = np.atleast_1d(as_finite_array(u, "u", ndim=(0, 1)))
        s = self.s
        ds = self._advance_canonical(u)
        if ds > 0.0:
            u_now, u_next = self.omega_fit * self._drive(np.array([s, s + ds]))
            phi, b0, b1 = _first_order_hold(self.omega_fit, ds, self.dmp.alpha_z)
            self.y, self.z = _hold_update(phi, np.stack([self.y, self.z]), _hold_inputs(b0, b1, u_now, u_next))
        return self.state

    @property
    def frequency(self) -> float:
        """The oscillator's adapted frequency Omega_A (rad/s)."""
        return self.oscillator.omega


def _canonical_key(dmp, transient: int) -> tuple[float, float, float, float]:
    """What a schedule takes from the DMP: ``(Omega, period, alpha_z, phi0)`` (its canonical system, damping and
    transient ``transient``'s start phase)."""
    return (float(dmp.canonical.omega), float(dmp.period), float(dmp.alpha_z),
            float(dmp.transients[dmp._check_transient(transient)].phi0))


#: the canonical system's state that a schedule keeps per step: the stepper's canonical time, time, rate and smoothed
#: frequency, the oscillator's phase and frequency
_STATE = ("s", "time", "rate", "smoothed_frequency", "oscillator_phase", "oscillator_omega")


def _samples(u: np.ndarray) -> np.ndarray:
    """The input samples ``u [T]`` or ``[T, k]`` as ``[T, k]`` (finite)."""
    samples = as_finite_array(u, "u", ndim=(1, 2))
    return samples.reshape(len(samples), -1)


def _check_stop_step(stop_step: int | None, n: int) -> None:
    if stop_step is not None and not (isinstance(stop_step, (int, np.integer)) and 0 <= stop_step < n):
        raise ValueError(f"stop_step: expected a step in [0, {n}) or None, got {stop_step!r}")


def _check_retunes(retunes: Any) -> None:
    if retunes is not None and not isinstance(retunes, Retunes):
        raise TypeError(f"retunes: expected a Retunes or None, got {type(retunes).__name__}")


def _state_of(stepper: AdaptiveFrequencyStepper) -> tuple[float, ...]:
    """The stepper's canonical state (:data:`_STATE`)."""
    return (stepper.s, stepper.time, stepper.rate, stepper.smoothed_frequency, stepper.oscillator.phase,
            stepper.oscillator.omega)


def _set_state(stepper: AdaptiveFrequencyStepper, values: np.ndarray) -> None:
    """Put the stepper in the canonical state ``values [6]`` (:data:`_STATE`, as :func:`_state_of` gives it)."""
    (stepper.s, stepper.time, stepper.rate, stepper.smoothed_frequency, stepper.oscillator.phase,
     stepper.oscillator.omega) = (float(value) for value in values)


def _restored_stepper(schedule: CanonicalSchedule, dmp, step: int, settings: Mapping[str, Any],
                      retune: float | None = None) -> AdaptiveFrequencyStepper:
    """A stepper of ``dmp`` with ``settings`` in the canonical state that ``schedule`` recorded before step ``step``:
    its state (:data:`_STATE`) and the oscillator's inputs so far (the last period's window is all it reads); with
    ``retune`` (rad/s) its oscillator's frequency and the smoothed one the DMP follows set to it."""
    stepper = AdaptiveFrequencyStepper(dmp, schedule.dt, **settings)
    if _canonical_key(dmp, stepper.transient) != schedule.canonical:
        raise ValueError("dmp: its canonical system, damping or start phase differs from the recorded DMP's")
    _set_state(stepper, schedule.states[step])
    oscillator = stepper.oscillator
    kept = schedule.u[max(0, step - oscillator._capacity): step]
    if len(kept):
        oscillator._history = np.empty((2 * oscillator._capacity, schedule.u.shape[1]))
        oscillator._history[: len(kept)] = kept
        oscillator._used = len(kept)
    if retune is not None:
        stepper.oscillator.omega = stepper.smoothed_frequency = check_positive(retune, "retune")
    return stepper


@dataclass(frozen=True, eq=False)
class Retunes:
    """Corrections of a follower's frequency at given steps: before step ``steps[j]`` the oscillator's frequency and
    the smoothed one the DMP follows move the share ``gain`` of the way to ``targets[j]`` (rad/s), ``omega <- omega
    + gain (target - omega)`` (a listener that hears the input's tempo and corrects its own by that share).

    Attributes:
        steps: ``[J]`` strictly increasing steps (>= 0).
        targets: ``[J]`` the frequencies heard there (rad/s, > 0).
        gain: the share in ``(0, 1]``.
    """

    steps: np.ndarray
    targets: np.ndarray
    gain: float

    def __post_init__(self) -> None:
        steps = np.asarray(self.steps)
        if steps.ndim != 1 or not np.issubdtype(steps.dtype, np.integer) or np.any(steps < 0) \
                or np.any(np.diff(steps) <= 0):
            raise ValueError(f"steps: expected strictly increasing integer steps >= 0 [J], got {self.steps!r}")
        targets = as_finite_array(self.targets, "targets", ndim=1)
        if targets.shape != steps.shape or np.any(targets <= 0):
            raise ValueError(f"targets: expected {steps.size} frequencies > 0 (rad/s), one per step, got "
                             f"{self.targets!r}")
        if not (np.isfinite(self.gain) and 0.0 < self.gain <= 1.0):
            raise ValueError(f"gain: expected a share in (0, 1], got {self.gain!r}")
        object.__setattr__(self, "steps", steps.astype(np.int64))
        object.__setattr__(self, "targets", targets.astype(np.float64))

    def __eq__(self, other: object) -> bool:
        return (isinstance(other, Retunes) and self.gain == other.gain and np.array_equal(self.steps, other.steps)
                and np.array_equal(self.targets, other.targets))

    __hash__ = None  # type: ignore[assignment]

    def at(self) -> dict[int, float]:
        """``{step: target}``."""
        return dict(zip(self.steps.tolist(), self.targets.tolist(), strict=True))


def _apply_retune(stepper: AdaptiveFrequencyStepper, target: float, gain: float) -> None:
    """Move the stepper's oscillator frequency and smoothed frequency the share ``gain`` towards ``target``."""
    stepper.oscillator.omega += gain * (target - stepper.oscillator.omega)
    stepper.smoothed_frequency += gain * (target - stepper.smoothed_frequency)


@dataclass(frozen=True, eq=False)
class CanonicalSchedule:
    """The canonical time of one run of an :class:`AdaptiveFrequencyStepper` over an input recording, for the
    transformation system of other parameters to follow.

    The canonical time (the oscillator, the rate, each step ``ds`` and the canonical time of a stop request)
    depends on the input, the stepper's settings and the DMP's canonical system, damping and start phase, not on
    what drives the transformation system: the forcing weights, the amplitude, the ending's weights and goal.
    Given it, the transformation system is linear. :meth:`record` runs the canonical system alone;
    :meth:`rollout` integrates the transformation system of a DMP along it with the stepper's own operations, so
    its path equals the stepper's bit for bit; :meth:`matches` says whether a run would record this schedule;
    :meth:`resume` continues a schedule from one of its steps with other settings or another input (a change of the
    rhythm's gains or shift at a cycle's start: the oscillator goes on from where it is, not from the start).

    Attributes:
        u: ``[T, k]`` the input samples (read-only).
        dt: the sample period (s).
        stop_step: the step before which the stop is requested (``None``: no stop).
        settings: the stepper's keywords.
        canonical: what the schedule takes from the DMP (:func:`_canonical_key`).
        s: ``[T + 1]`` the canonical time before each step and after the last.
        ds: ``[T]`` each step's advance of the canonical time (0: the DMP stands still over the step).
        hold: each step's first-order hold (:func:`_first_order_hold`): ``Phi [T, 2, 2]``, ``B0 [T, 2]``,
            ``B1 [T, 2]`` (zeros where ``ds = 0``).
        states: ``[T + 1, 6]`` the canonical system's state before each step and after the last
            (:data:`_STATE`: what :meth:`resume` restores).
        since: the first step that ran with these settings and input (0, or the step :meth:`resume` went on from).
        retunes: the follower's scheduled frequency corrections (:class:`Retunes`; None: none).
    """

    u: np.ndarray
    dt: float
    stop_step: int | None
    settings: Mapping[str, Any]
    canonical: tuple[float, float, float, float]
    s: np.ndarray
    ds: np.ndarray
    hold: tuple[np.ndarray, np.ndarray, np.ndarray]
    states: np.ndarray
    since: int = 0
    retunes: Retunes | None = None

    @classmethod
    def record(cls, dmp, u: np.ndarray, dt: float, stop_step: int | None = None, retunes: Retunes | None = None,
               **settings: Any) -> CanonicalSchedule:
        """The schedule of ``AdaptiveFrequencyStepper(dmp, dt, **settings)`` stepped over the samples ``u`` (``[T]``
        or ``[T, k]``), its stop requested before step ``stop_step`` (in ``[0, T)``; ``None``: no stop), its
        frequency corrected by ``retunes`` (:class:`Retunes`; None: never)."""
        samples = _samples(u)
        _check_stop_step(stop_step, len(samples))
        _check_retunes(retunes)
        stepper = AdaptiveFrequencyStepper(dmp, dt, **settings)
        return cls._run(stepper, samples, 0, None, stop_step, dict(settings), _canonical_key(dmp, stepper.transient),
                        retunes)

    def resume(self, dmp, step: int, u: np.ndarray, retune: float | None = None,
               retunes: Retunes | str | None = "recorded", **settings: Any) -> CanonicalSchedule:
        """This schedule up to step ``step`` (in ``[0, T]``), then ``AdaptiveFrequencyStepper(dmp, dt, **settings)``
        going on from the recorded state there over the samples ``u [T]`` or ``[T, k]`` from ``step`` on (those
        before it are the recorded ones); ``dmp`` shares the recorded canonical system, and ``transient`` and
        ``frequency`` stay as recorded. ``retune`` (rad/s, > 0): the follower's frequency from ``step`` on (the
        oscillator's and the one the DMP follows; None: they go on as recorded); ``retunes``: the corrections of the
        steps after ``step`` (:class:`Retunes` or None; default the recorded ones). With the recorded settings,
        input and corrections and no retune it is this schedule, bit for bit."""
        samples = _samples(u)
        n = self.ds.size
        if samples.shape != self.u.shape:
            raise ValueError(f"u: expected {self.u.shape[0]} samples of {self.u.shape[1]} value(s), as recorded, got "
                             f"shape {np.shape(u)}")
        if not (isinstance(step, (int, np.integer)) and 0 <= step <= n):
            raise ValueError(f"step: expected a step in [0, {n}], got {step!r}")
        for key in ("transient", "frequency"):
            if settings.get(key) != self.settings.get(key):
                raise ValueError(f"settings: {key} is the schedule's start ({self.settings.get(key)!r}); a resumed "
                                 f"schedule cannot change it (got {settings.get(key)!r})")
        retunes = self.retunes if isinstance(retunes, str) and retunes == "recorded" else retunes
        _check_retunes(retunes)
        stepper = _restored_stepper(self, dmp, int(step), settings, retune)
        joined = np.concatenate([self.u[:step], samples[step:]])
        return self._run(stepper, joined, int(step), self, self.stop_step, dict(settings), self.canonical, retunes)

    @classmethod
    def _run(cls, stepper: AdaptiveFrequencyStepper, samples: np.ndarray, start: int,
             before: CanonicalSchedule | None, stop_step: int | None, settings: dict[str, Any],
             canonical: tuple[float, float, float, float], retunes: Retunes | None = None) -> CanonicalSchedule:
        """Step ``stepper`` over ``samples [T, k]`` from step ``start`` on, the steps before it copied from
        ``before``, its frequency corrected before the steps of ``retunes`` from ``start`` on; the schedule."""
        n = len(samples)
        s, ds = np.empty(n + 1), np.zeros(n)
        phi, b0, b1 = np.zeros((n, 2, 2)), np.zeros((n, 2)), np.zeros((n, 2))
        states = np.empty((n + 1, len(_STATE)))
        if before is not None:
            s[:start], ds[:start], states[:start] = before.s[:start], before.ds[:start], before.states[:start]
            for mine, theirs in zip((phi, b0, b1), before.hold, strict=True):
                mine[:start] = theirs[:start]
        alpha_z = canonical[2]
        corrections = {} if retunes is None else retunes.at()
        for k in range(start, n):
            if k in corrections and (before is None or k > start):     # a resumed state holds its step's own
                _apply_retune(stepper, corrections[k], retunes.gain)
            s[k], states[k] = stepper.s, _state_of(stepper)
            step = stepper._advance_canonical(samples[k])
            if step > 0.0:
                ds[k] = step
                phi[k], b0[k], b1[k] = _first_order_hold(stepper.omega_fit, step, alpha_z)
        s[n], states[n] = stepper.s, _state_of(stepper)
        arrays = (samples.copy(), s, ds, phi, b0, b1, states)
        for array in arrays:
            array.flags.writeable = False
        return cls(arrays[0], stepper.dt, None if stop_step is None else int(stop_step), settings, canonical, s, ds,
                   (phi, b0, b1), states, start, retunes)

    def matches(self, dmp, u: np.ndarray, dt: float, stop_step: int | None = None, retunes: Retunes | None = None,
                **settings: Any) -> bool:
        """Whether :meth:`record` with these arguments would record this schedule (the same input, sample period,
        stop step, corrections, settings and canonical system; ``dmp``'s weights, amplitude and ending may differ); a
        resumed schedule is no record's."""
        samples = np.asarray(u, dtype=np.float64)
        return (self.since == 0 and float(dt) == self.dt and stop_step == self.stop_step
                and retunes == self.retunes and dict(settings) == self.settings
                and samples.size == self.u.size and np.array_equal(samples.reshape(self.u.shape), self.u)
                and _canonical_key(dmp, settings.get("transient", 0)) == self.canonical)

    def rollout(self, dmp) -> np.ndarray:
        """The positions ``y [T + 1, d]`` before each step and after the last of
        ``AdaptiveFrequencyStepper(dmp, dt, **settings)`` stepped along this schedule, bit for bit; ``dmp`` shares
        the recorded DMP's canonical system, damping and start phase (its weights, amplitude and ending may differ).
        The drive and the input terms are computed for all steps at once, then the 2x2 updates run."""
        stepper = AdaptiveFrequencyStepper(dmp, self.dt, **self.settings)
        if _canonical_key(dmp, stepper.transient) != self.canonical:
            raise ValueError("dmp: its canonical system, damping or start phase differs from the recorded DMP's")
        n = self.ds.size
        cut = n if self.stop_step is None else self.stop_step
        ends = np.empty((2, n, dmp.n_dims))                 # the drive times Omega at each step's start and end
        before = stepper.omega_fit * stepper._drive(self.s[: cut + 1])
        ends[0, :cut], ends[1, :cut] = before[:-1], before[1:]
        if cut < n:                                         # the stop's steps
            stepper._set_stop(self.s[cut])
            after = stepper.omega_fit * stepper._drive(self.s[cut:])
            ends[0, cut:], ends[1, cut:] = after[:-1], after[1:]
        phi, b0, b1 = self.hold
        now, following = _hold_inputs(b0, b1, ends[0], ends[1])
        y = np.empty((n + 1, dmp.n_dims))
        y[0], state = stepper.y, np.stack([stepper.y, stepper.z])
        for k, moving in enumerate((self.ds > 0.0).tolist()):
            if moving:
                state = _hold_update(phi[k], state, (now[k], following[k]))
            y[k + 1] = state[0]
        return y


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
