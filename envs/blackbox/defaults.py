"""Defaults of the rhythmic black-box wrapper: the action scales, the default pattern, settings per known env, and
the settings derived from a MuJoCo model.

Without a demonstration the wrapper fits its DMP to :func:`default_demonstration`: one sine per joint about a
posture, the same period for all, each joint with its own phase, that grows from rest at the posture over its start
(a smoothstep envelope; one period unless the setting ``start_periods`` says less), so the fitted transient is a
gentle start into the rhythm.

On a MuJoCo env the settings not given (and not in :data:`ENV_DEFAULTS`) come from the model
(:func:`model_defaults`, the rules in :data:`MODEL_RULES`), so that any Gymnasium MuJoCo env with a continuous action
space runs with no option.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from rdmp_gym import Demonstration, Segmentation
from rdmp_gym.dmp.fitting import MIN_TRANSIENT

__all__ = ["BLACKBOX_SCALES", "ENV_DEFAULTS", "MIN_START", "MODEL_RULES", "ModelDefaults", "check_start",
           "default_demonstration", "env_defaults", "model_defaults", "pattern_phases"]

#: Action scales (``theta = theta0 + scale * a``). ``periodic``/``transient``: the fraction of the range of the
#: initial DMP's weights per joint (as :class:`rdmp_gym.envs.action.ActionMap` does); ``initial``: of pi for the
#: phase and of r0 for the radius; ``amplitude``: the factor on the pattern about the anchor, so ``a = +-1`` scales
#: it by 1.5 / 0.5; ``anchor``: the fraction of each joint's peak-to-peak motion in the initial DMP's cycle
#: (floored at a quarter of the largest joint's), so the unit-free value suits hinges (rad) and slides (m) alike;
#: ``tempo``: the change of the speed factor at ``a = +-1`` (0.5: 1.5x faster / half speed); ``feedback`` (the
#: setting ``feedback="linear"``): a gain from observation feature j to action i of ``a`` times ``scale h_i /
#: sqrt(m)`` action units per standard deviation (``h_i`` half the action box's width, ``m`` the features), so a row
#: of unit gains against deviations of one standard deviation, uncorrelated, commands about ``scale`` of the
#: half-width (RMS).
BLACKBOX_SCALES: dict[str, float] = {"periodic": 0.5, "transient": 0.5, "initial": 0.1, "amplitude": 0.5,
                                     "anchor": 0.5, "tempo": 0.5, "feedback": 0.25}

#: the shortest start of the default pattern (periods): the shortest transient a rhythmic DMP is fitted to
MIN_START = MIN_TRANSIENT

#: Settings of the wrapper for Gymnasium MuJoCo envs, by the env spec's name (no version); keywords given to
#: :func:`~rdmp_gym.envs.blackbox.make_blackbox` replace them. Both follow the open-loop baseline of Raffin et al.
#: 2024 (An Open-Loop Baseline for Reinforcement Learning Locomotion Tasks, arXiv 2310.05808,
#: https://arxiv.org/html/2310.05808v3): one sine per joint, one frequency shared by all joints, a phase per joint,
#: tracked by a PD controller on the env's torque action (``benchmarks/results/open_loop_oscillator.json`` holds the
#: returns quoted here and the baseline re-run with CMA-ES).
#:
#: - ``Swimmer``: their published oscillator (0.62 Hz, phases 0 and 0.95 x 2 pi, amplitude 1 rad, PD gains 10 and
#:   0.5 in action units per rad and rad/s; the code on their RLC 2024 slides) with a start from rest of a tenth of
#:   a period. The return of ``a = 0`` on Swimmer-v5 (1,000 steps, reset seeds 0-9) is 352.3, their oscillator's
#:   own 352.1 (``benchmarks/results/open_loop_oscillator.json``, "references"); with a start of one period it is
#:   345.6 (the slow start is what costs), with half their amplitude and that start 109.3.
#: - ``HalfCheetah``: no gait of theirs was found in the sources at hand; their PD gains (1 action unit per rad, the
#:   motors' gears are 30-120 Nm, and 0.05 per rad/s) with a gait found by their method: one frequency, and per joint
#:   (``bthigh, bshin, bfoot, fthigh, fshin, ffoot``) an amplitude, a phase and an offset (the posture), tuned by
#:   CMA-ES on the raw env (``benchmarks/bench_open_loop_oscillator.py --split off``, seed 9's best candidate, 3.81
#:   Hz; the phases moved back by one env step, as the wrapper's PD aims at the end of each step). Of the five runs'
#:   best candidates with the highest test returns it is the one that stays upright under the wrapper (the other four
#:   turn the cheetah onto its back). The return of ``a = 0`` on HalfCheetah-v5 is 1194 on reset seeds 0-9 (1242 on
#:   10-29; tracking RMS 0.33 rad, 4 % of the commands clipped); a wave about the reset posture (3 Hz, joint j at
#:   phase j pi / 3, 0.5 rad, gains 1 / 0.02, the best of 132 such settings) returns 648.
ENV_DEFAULTS: dict[str, dict[str, Any]] = {
    "Swimmer": {"controller": "pd", "p_gains": 10.0, "d_gains": 0.5, "period": 1.0 / 0.62,
                "phases": (0.0, 0.95 * 2.0 * np.pi), "amplitude": 1.0, "start_periods": 0.1},
    "HalfCheetah": {"controller": "pd", "p_gains": 1.0, "d_gains": 0.05, "period": 1.0 / 3.81,
                    "amplitude": (0.695, 0.326, 0.457, 0.628, 0.959, 0.253),
                    "phases": (-0.883, 1.764, 4.283, -0.674, 0.686, 3.952),
                    "posture": (0.345, -0.302, 0.078, -0.086, -0.110, 0.113)},
}


def env_defaults(env_id: str) -> dict[str, Any]:
    """A copy of :data:`ENV_DEFAULTS` for ``env_id`` (``"Swimmer-v5"``, ``"gymnasium/Swimmer-v5"``, or a name
    without version); ``{}`` for an env without entry."""
    name = env_id.rsplit("/", 1)[-1].rsplit(":", 1)[-1]
    head, _, version = name.rpartition("-v")
    if head and version.isdigit():
        name = head
    return dict(ENV_DEFAULTS.get(name, {}))


def pattern_phases(phases: float | Sequence[float] | None, n_joints: int) -> np.ndarray:
    """``[d]`` phases (rad) of the default pattern's sines: given per joint, or a number ``lag``: joint j at
    ``-j * lag`` (a wave travelling from the first joint to the last); ``None``: a lag of pi/2."""
    if phases is None:
        phases = 0.5 * np.pi
    values = np.asarray(phases, dtype=np.float64)
    if values.ndim == 0:
        values = -float(values) * np.arange(n_joints)
    if values.shape != (n_joints,) or not np.all(np.isfinite(values)):
        raise ValueError(f"phases: expected a number (the lag between neighbouring joints) or {n_joints} finite "
                         f"phases (rad), got {phases!r}")
    return values


def default_demonstration(posture: np.ndarray, period: float, amplitude: float | Sequence[float],
                          phases: float | Sequence[float] | None = None, rate: float = 100.0,
                          cycles: int = 4, start: float = 1.0) -> tuple[Demonstration, Segmentation]:
    """The default pattern and its segmentation: ``y_j(t) = posture_j + s(t / (c T)) A_j sin(2 pi t / T + phi_j)``.

    Args:
        posture: ``[d]`` the anchor (the joints' rest posture).
        period: T (s).
        amplitude: ``A`` (joint units), a number or ``[d]``, each > 0.
        phases: see :func:`pattern_phases`.
        rate: samples per second.
        cycles: whole periods after the start.
        start: ``c``, the start's length (the transient, over which the envelope ``s`` grows from 0 to 1) in
            periods, at least :data:`MIN_START`.
    Returns:
        the demonstration (starting at rest at the posture) and its known segmentation.
    """
    posture = np.asarray(posture, dtype=np.float64)
    if posture.ndim != 1 or posture.size == 0 or not np.all(np.isfinite(posture)):
        raise ValueError(f"posture: expected [d] finite joint positions, got {posture!r}")
    d = posture.size
    period = float(period)
    if not (np.isfinite(period) and period > 0.0):
        raise ValueError(f"period: expected a duration > 0 s, got {period!r}")
    amplitudes = np.broadcast_to(np.asarray(amplitude, dtype=np.float64), (d,)) if np.ndim(amplitude) == 0 \
        else np.asarray(amplitude, dtype=np.float64)
    if amplitudes.shape != (d,) or not np.all(np.isfinite(amplitudes)) or np.any(amplitudes <= 0.0):
        raise ValueError(f"amplitude: expected a number or {d} numbers > 0 (joint units), got {amplitude!r}")
    phi = pattern_phases(phases, d)
    start = check_start(start)
    t = np.arange(round((cycles + start) * period * rate) + 1) / rate
    u = np.clip(t / (start * period), 0.0, 1.0)
    envelope = u**3 * (10.0 - 15.0 * u + 6.0 * u**2)
    Y = posture + envelope[:, None] * amplitudes * np.sin(2.0 * np.pi * t[:, None] / period + phi)
    return (Demonstration(t, Y, name="default rhythmic pattern"),
            Segmentation(period=period, transient_length=start * period, anchor=posture.copy()))


def check_start(start: object, name: str = "start") -> float:
    """``start`` (the default pattern's start in periods) as a float >= :data:`MIN_START`; ValueError naming
    ``name``."""
    if isinstance(start, bool) or not isinstance(start, (int, float, np.integer, np.floating)) \
            or not (np.isfinite(start) and float(start) >= MIN_START):
        raise ValueError(f"{name}: expected the default pattern's start from rest in periods, a number >= "
                         f"{MIN_START:g}, got {start!r}")
    return float(start)


#: The rules of :func:`model_defaults` (fractions of a joint's range; a joint without limits counts as 2 pi for a
#: hinge and the model's length for a slide):
#:
#: - ``full_command_error``: the PD gives the full command (the action box's half width) at this error;
#: - ``stability``: at most this many rad of the PD's natural frequency per env step (the stiffness is capped at
#:   ``inertia * (stability / dt)**2``, so the sampled loop stays well damped);
#: - ``amplitude``: the default pattern's amplitude; ``hold_amplitude`` on a model with passive joints;
#: - ``hold_periods``: on a model with passive joints, the period is this many natural periods.
MODEL_RULES: dict[str, float] = {"full_command_error": 0.1, "stability": 0.5, "amplitude": 0.04,
                                 "hold_amplitude": 0.001, "hold_periods": 3.0}

#: standard gravity (m/s^2): the natural period's length-to-time scale, also for models without gravity
_G0 = 9.81


@dataclass(frozen=True, eq=False)
class ModelDefaults:
    """The wrapper's settings derived from a MuJoCo model, per actuated joint (``[d]``, in the action's order).

    Attributes:
        controller: ``"pd"`` (motors), ``"position"`` or ``"velocity"`` (servos with gear 1), or None with
            :attr:`no_controller` saying why.
        no_controller: why the actuators get no built-in controller ("" where they do).
        p_gains, d_gains: ``[d]`` the PD's gains in action units per joint unit (and per joint unit/s); None
            unless ``controller == "pd"``.
        posture: ``[d]`` the reset posture ``init_qpos`` at the joints, inside the limited joints' ranges.
        amplitude: ``[d]`` the default pattern's amplitude (joint units).
        period: the default pattern's period (s).
        inertia: ``[d]`` each joint's effective inertia at the posture, ``1 / (M^-1)_jj`` of the joint-space
            inertia matrix ``M`` (armature included; kg m^2 or kg): what its torque meets with the rest free.
        force_per_command: ``[d]`` joint torque (or force) per unit of the action (gear x actuator gain).
        joint_range: ``[d]`` each joint's range (a joint without limits: 2 pi, or the model's length for a slide).
        length: the model's length (m): twice the radius of gyration of its moving bodies at the posture.
        passive: the names of the model's passive joints (unactuated hinges or slides of a body that hangs from
            another body, e.g. an inverted pendulum's pole), which make the pattern hold the posture.
    """

    controller: str | None
    no_controller: str
    p_gains: np.ndarray | None
    d_gains: np.ndarray | None
    posture: np.ndarray
    amplitude: np.ndarray
    period: float
    inertia: np.ndarray
    force_per_command: np.ndarray
    joint_range: np.ndarray
    length: float
    passive: tuple[str, ...]

    def critical_damping(self, p_gains: np.ndarray) -> np.ndarray:
        """``[d]`` the d gains (action units per joint unit/s) that damp the PD of ``p_gains [d]`` critically on the
        joints' inertia: ``2 sqrt(Kp g I) / g`` with ``g`` the force per command."""
        force = self.force_per_command
        return 2.0 * np.sqrt(np.asarray(p_gains, dtype=np.float64) * force * self.inertia) / force


def model_defaults(env: Any, joints: Any, dt: float) -> ModelDefaults:
    """The settings a MuJoCo env's model suggests for its actuated joints (the rules of :data:`MODEL_RULES`).

    - **controller**: motors (no bias) get ``"pd"``; position or velocity servos with gear 1 get ``"position"`` or
      ``"velocity"``; other or mixed actuators get none.
    - **PD gains**: the stiffness that gives the full command at ``full_command_error`` of the joint's range,
      ``K = g c / (0.1 range)`` (``g``: force per command, ``c``: half the action box), capped at
      ``I (stability / dt)^2`` (``I``: the joint's effective inertia at the posture, ``1 / (M^-1)_jj`` of the
      joint-space inertia matrix, armature included; the diagonal ``M_jj`` itself, the inertia with every other
      joint locked, overestimates it on a floating robot and lets the sampled loop chatter); the damping critical,
      ``D = 2 sqrt(K I)``; in action units, ``p = K / g`` and ``d = D / g``.
    - **posture**: ``init_qpos`` at the joints, inside their ranges.
    - **pattern**: amplitude ``amplitude`` x each joint's range, period the natural period
      ``T0 = 2 pi sqrt(l / g0)`` of the model's length ``l`` (twice the radius of gyration of its moving bodies);
      on a model with **passive joints** (a balancing system: an unactuated hinge or slide inside the body tree)
      the pattern holds the posture: amplitude ``hold_amplitude`` x the range and period ``hold_periods`` x T0
      (the DMP's start, one period long, then glides from the reset state to the posture).

    Args:
        env: the env (``env.unwrapped.model``, ``init_qpos``, ``action_space``).
        joints: its :class:`~rdmp_gym.envs.blackbox.controller.MujocoJoints`.
        dt: seconds per env step.
    """
    import mujoco

    base = env.unwrapped
    model = base.model
    data = mujoco.MjData(model)
    init = getattr(base, "init_qpos", None)
    data.qpos[:] = model.qpos0 if init is None else np.asarray(init, dtype=np.float64)
    mujoco.mj_forward(model, data)
    ids = joints.joint_ids
    length = _model_length(model, data)
    limited = np.asarray(model.jnt_limited[ids], dtype=bool)
    low, high = model.jnt_range[ids, 0], model.jnt_range[ids, 1]
    slide = model.jnt_type[ids] == int(mujoco.mjtJoint.mjJNT_SLIDE)
    joint_range = np.where(limited & (high > low), high - low, np.where(slide, length, 2.0 * np.pi))
    posture = data.qpos[joints.qpos_adr].copy()
    posture = np.where(limited, np.clip(posture, low, high), posture)
    inertia = _effective_inertia(model, data)[joints.dof_adr]
    force = model.actuator_gear[:, 0] * model.actuator_gainprm[:, 0]
    controller, why = _controller(model)
    p_gains, d_gains = _pd_gains(env.action_space, np.abs(force), joint_range, inertia, dt) if controller == "pd" \
        else (None, None)
    passive = _passive_joints(model)
    natural = 2.0 * np.pi * np.sqrt(length / _G0)
    hold = bool(passive)
    amplitude = MODEL_RULES["hold_amplitude" if hold else "amplitude"] * joint_range
    period = natural * (MODEL_RULES["hold_periods"] if hold else 1.0)
    return ModelDefaults(controller, why, p_gains, d_gains, posture, amplitude, float(period), inertia,
                         np.abs(force), joint_range, float(length), passive)


def _pd_gains(space: Any, force: np.ndarray, joint_range: np.ndarray, inertia: np.ndarray, dt: float
              ) -> tuple[np.ndarray, np.ndarray]:
    """``[d]`` p and d gains (action units): the stiffness of the full command at ``full_command_error`` of the
    range, capped for the sampled loop's stability, critically damped (see :func:`model_defaults`)."""
    width = np.asarray(space.high, dtype=np.float64) - np.asarray(space.low, dtype=np.float64)
    half = np.where(np.isfinite(width), width / 2.0, np.inf)
    stiffness = np.minimum(force * half / (MODEL_RULES["full_command_error"] * joint_range),
                           inertia * (MODEL_RULES["stability"] / dt) ** 2)
    return stiffness / force, 2.0 * np.sqrt(stiffness * inertia) / force


def _effective_inertia(model: Any, data: Any) -> np.ndarray:
    """``[nv]`` each degree of freedom's effective inertia ``1 / (M^-1)_jj``: what a torque on it alone meets with
    the rest of the model free to move (the joint-space inertia matrix ``M`` built one column ``M e_j`` at a
    time)."""
    import mujoco

    matrix, unit = np.empty((model.nv, model.nv)), np.zeros(model.nv)
    for index in range(model.nv):
        unit[:] = 0.0
        unit[index] = 1.0
        mujoco.mj_mulM(model, data, matrix[index], unit)     # M is symmetric: row j = column j
    return 1.0 / np.diag(np.linalg.inv(matrix))


def _model_length(model: Any, data: Any) -> float:
    """Twice the radius of gyration (m) of the moving bodies' mass about their centre of mass (the bodies' own
    inertia included); the model's mean size where nothing moves."""
    moving = [body for body in range(1, model.nbody) if model.body_weldid[body] != 0 and model.body_mass[body] > 0]
    if not moving:
        return float(model.stat.meansize)
    mass = model.body_mass[moving]
    centres = data.xipos[moving]
    centre = mass @ centres / mass.sum()
    spread = mass @ np.sum((centres - centre) ** 2, axis=1) + 0.5 * model.body_inertia[moving].sum()
    return float(2.0 * np.sqrt(spread / mass.sum()))


def _controller(model: Any) -> tuple[str | None, str]:
    """The built-in controller the actuators suit, or None and why not."""
    import mujoco

    fixed, none, affine = (int(mujoco.mjtGain.mjGAIN_FIXED), int(mujoco.mjtBias.mjBIAS_NONE),
                           int(mujoco.mjtBias.mjBIAS_AFFINE))
    kinds = []
    for index in range(model.nu):
        gain, bias = model.actuator_gainprm[index, 0], model.actuator_biasprm[index, :3]
        if int(model.actuator_gaintype[index]) != fixed:
            kinds.append("other")
        elif int(model.actuator_biastype[index]) == none:
            kinds.append("pd" if gain * model.actuator_gear[index, 0] != 0.0 else "other")
        elif int(model.actuator_biastype[index]) == affine and bias[0] == 0.0 and gain != 0.0 and bias[1] == -gain:
            kinds.append("position")
        elif int(model.actuator_biastype[index]) == affine and bias[0] == bias[1] == 0.0 and gain != 0.0 \
                and bias[2] == -gain:
            kinds.append("velocity")
        else:
            kinds.append("other")
    found = sorted(set(kinds))
    if len(found) != 1 or found[0] == "other":
        return None, (f"the actuators are not all motors, or all position or velocity servos ({', '.join(found)}); "
                      "pass controller='pd' with p_gains, or a callable (q_des, qd_des, q, qd) -> action")
    if found[0] != "pd" and not np.all(model.actuator_gear[:, 0] == 1.0):
        return None, (f"the {found[0]} servos have a gear other than 1 (their command is gear x the joint's "
                      f"{found[0]}); pass a controller callable (q_des, qd_des, q, qd) -> action")
    return found[0], ""


def _passive_joints(model: Any) -> tuple[str, ...]:
    """The names of the unactuated hinge and slide joints of bodies whose parent is not the world (the root joints
    of a floating robot hang from the world and are not passive)."""
    import mujoco

    driven = {int(model.actuator_trnid[index, 0]) for index in range(model.nu)
              if int(model.actuator_trntype[index]) == int(mujoco.mjtTrn.mjTRN_JOINT)}
    kinds = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))
    return tuple(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, joint) or f"joint {joint}"
                 for joint in range(model.njnt)
                 if joint not in driven and int(model.jnt_type[joint]) in kinds
                 and int(model.body_parentid[model.jnt_bodyid[joint]]) != 0)
