"""Joint state readers and tracking controllers of the rhythmic black-box wrapper.

A **joint state reader** is a callable ``reader(env) -> (q [d], qd [d])``: the positions and velocities of the d
joints the DMP drives. :class:`MujocoJoints` is the default for Gymnasium MuJoCo envs: the joint that each
actuator drives (``model.actuator_trnid``), read from ``env.unwrapped.data.qpos`` / ``qvel``.

A **tracking controller** is a callable ``controller(q_des, qd_des, q, qd) -> action``: the env's action that moves
the joints from their state ``(q, qd)`` towards the desired state ``(q_des, qd_des)`` at the end of the env step. The
wrapper clips its result to the env's action box. :func:`make_controller` builds the three built-in ones:

- ``"pd"``: ``Kp (q_des - q) + Kd (qd_des - qd)``, for envs whose action is a joint torque (or motor command);
- ``"position"``: ``q_des``, for envs whose action is a joint position target;
- ``"velocity"``: ``qd_des + Kp (q_des - q)`` (``Kp`` = 0 by default: ``qd_des`` itself), for joint velocity targets.

With the wrapper's setting ``feedback="linear"`` a :class:`LinearFeedback` adds ``K z`` to the controller's command:
``z`` the env's observation standardised on a reference gait, ``K`` gains the policy learns.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

__all__ = ["CONTROLLERS", "JointReader", "LinearFeedback", "MujocoJoints", "PDController", "PositionController",
           "TrackingController", "VelocityController", "check_gains", "make_controller"]

#: ``reader(env) -> (q [d], qd [d])``
JointReader = Callable[[Any], tuple[np.ndarray, np.ndarray]]
#: ``controller(q_des [d], qd_des [d], q [d], qd [d]) -> action [n]``
TrackingController = Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], np.ndarray]

CONTROLLERS = ("pd", "position", "velocity")

#: the standardised observation is clipped to +- this many standard deviations of the reference gait
FEEDBACK_CLIP = 5.0
#: a feature's standard deviation is floored at this fraction of the median one (1 where the median is 0): a feature
#: that is constant on the reference gait would otherwise turn any deviation into the clip
FEEDBACK_STD_FLOOR = 0.01


class MujocoJoints:
    """The joints of a Gymnasium MuJoCo env's actuators, one per actuator, in the action's order.

    Every actuator must drive a hinge or slide joint directly (``actuator_trntype`` joint); tendons, sites,
    free and ball joints have no single joint coordinate to track, and raise ``ValueError``.

    Args:
        env: the env (``env.unwrapped.model`` and ``data``).

    Attributes:
        joint_ids: ``[d]`` the joints' ids in the model.
        qpos_adr, dof_adr: ``[d]`` the joints' addresses in ``data.qpos`` and ``data.qvel``.
        names: the joints' names.
    """

    def __init__(self, env: Any) -> None:
        import mujoco  # the env is a MuJoCo env, so mujoco is installed

        base = env.unwrapped
        model = base.model
        if model.nu == 0:
            raise ValueError("joint_state: the MuJoCo model has no actuators, so there are no actuated joints to track")
        joints = []
        for index in range(model.nu):
            name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, index) or f"actuator {index}"
            if int(model.actuator_trntype[index]) != int(mujoco.mjtTrn.mjTRN_JOINT):
                raise ValueError(f"joint_state: actuator {name!r} does not drive a joint directly (transmission "
                                 f"{mujoco.mjtTrn(model.actuator_trntype[index]).name}); pass "
                                 "joint_state=callable(env) -> (q, qd)")
            joint = int(model.actuator_trnid[index, 0])
            kind = int(model.jnt_type[joint])
            if kind not in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE)):
                raise ValueError(f"joint_state: actuator {name!r} drives a {mujoco.mjtJoint(kind).name} joint, not a "
                                 "hinge or slide; pass joint_state=callable(env) -> (q, qd)")
            joints.append(joint)
        self.joint_ids = np.array(joints, dtype=np.intp)
        self.qpos_adr = np.array([model.jnt_qposadr[j] for j in joints], dtype=np.intp)
        self.dof_adr = np.array([model.jnt_dofadr[j] for j in joints], dtype=np.intp)
        self.names = tuple(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) or f"joint {j}" for j in joints)

    @staticmethod
    def available(env: Any) -> bool:
        """Whether ``env.unwrapped`` has a MuJoCo ``model`` and ``data`` to read."""
        base = env.unwrapped
        return hasattr(base, "model") and hasattr(base, "data") and hasattr(base.model, "actuator_trnid")

    def __call__(self, env: Any) -> tuple[np.ndarray, np.ndarray]:
        data = env.unwrapped.data
        return data.qpos[self.qpos_adr].copy(), data.qvel[self.dof_adr].copy()


def check_gains(gains: Any, n_joints: int, name: str) -> np.ndarray:
    """``[d]`` gains from a number or ``d`` numbers, each finite and >= 0; ``ValueError`` naming ``name``."""
    try:
        values = np.asarray(gains, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise ValueError(f"{name}: expected a number or {n_joints} numbers >= 0, got {gains!r}") from error
    if values.ndim == 0:
        values = np.full(n_joints, float(values))
    if values.shape != (n_joints,) or not np.all(np.isfinite(values)) or np.any(values < 0.0):
        raise ValueError(f"{name}: expected a number or {n_joints} finite numbers >= 0, got {gains!r}")
    return values


class PDController:
    """``Kp (q_des - q) + Kd (qd_des - qd)``: torques (in the env's action units) from the tracking error."""

    name = "pd"

    def __init__(self, p_gains: np.ndarray, d_gains: np.ndarray) -> None:
        self.p_gains, self.d_gains = p_gains, d_gains

    def __call__(self, q_des: np.ndarray, qd_des: np.ndarray, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        return self.p_gains * (q_des - q) + self.d_gains * (qd_des - qd)


class PositionController:
    """``q_des``: the desired joint positions are the env's action (a position target)."""

    name = "position"

    def __call__(self, q_des: np.ndarray, qd_des: np.ndarray, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        return q_des.copy()


class VelocityController:
    """``qd_des + Kp (q_des - q)``: the desired joint velocities (with an optional position correction) are the
    env's action (a velocity target)."""

    name = "velocity"

    def __init__(self, p_gains: np.ndarray) -> None:
        self.p_gains = p_gains

    def __call__(self, q_des: np.ndarray, qd_des: np.ndarray, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        return qd_des + self.p_gains * (q_des - q)


def make_controller(controller: str | TrackingController, n_joints: int, n_actions: int, p_gains: Any = None,
                    d_gains: Any = None) -> TrackingController:
    """The tracking controller named ``controller`` (one of :data:`CONTROLLERS`), or ``controller`` itself if it is a
    callable (then the gains are not used).

    The built-in controllers give one action per joint: ``n_actions`` must equal ``n_joints``. ``"pd"`` needs
    ``p_gains`` (``d_gains`` default 0); ``"velocity"`` takes optional ``p_gains`` (default 0); ``"position"`` takes
    none.
    """
    if callable(controller):
        if p_gains is not None or d_gains is not None:
            raise ValueError("p_gains/d_gains: only used by the built-in controllers, not by a controller callable")
        return controller
    if controller not in CONTROLLERS:
        raise ValueError(f"controller: expected one of {CONTROLLERS} or a callable (q_des, qd_des, q, qd) -> action, "
                         f"got {controller!r}")
    if n_actions != n_joints:
        raise ValueError(f"controller: {controller!r} gives one action per joint, but the env has {n_actions} action "
                         f"dimensions for {n_joints} joints; pass a controller callable (q_des, qd_des, q, qd) -> "
                         "action")
    if controller == "pd":
        if p_gains is None:
            raise ValueError("p_gains: the 'pd' controller needs its position gains (action units per joint unit) and "
                             "the env has no MuJoCo motors to derive them from; pass p_gains=... (a number or one per "
                             "joint)")
        return PDController(check_gains(p_gains, n_joints, "p_gains"),
                            check_gains(0.0 if d_gains is None else d_gains, n_joints, "d_gains"))
    if d_gains is not None:
        raise ValueError(f"d_gains: the {controller!r} controller has no velocity gains")
    if controller == "position":
        if p_gains is not None:
            raise ValueError("p_gains: the 'position' controller passes the desired positions through; it has no gains")
        return PositionController()
    return VelocityController(check_gains(0.0 if p_gains is None else p_gains, n_joints, "p_gains"))


class LinearFeedback:
    """The reacting term ``K z`` added to the tracking controller's command: ``z = clip((o - mean) / std, +-5)``.

    ``mean`` and ``std`` ``[m]`` are the flattened observation's statistics over a reference rollout (the wrapper's
    ``a = 0`` gait), fixed when the wrapper is built, so ``z`` measures how far the body is from its nominal gait in
    that gait's own standard deviations.

    Args:
        observations: ``[N, m]`` the reference rollout's flattened observations.
    """

    def __init__(self, observations: np.ndarray) -> None:
        values = np.asarray(observations, dtype=np.float64)
        if values.ndim != 2 or values.shape[0] == 0 or not np.all(np.isfinite(values)):
            raise ValueError(f"feedback: expected [N, m] finite reference observations, got shape {values.shape}")
        self.mean = values.mean(axis=0)
        spread = values.std(axis=0)
        median = float(np.median(spread))
        self.std = np.maximum(spread, FEEDBACK_STD_FLOOR * median if median > 0.0 else 1.0)

    @property
    def n_features(self) -> int:
        """m, the observation features."""
        return int(self.mean.size)

    def features(self, observation: np.ndarray) -> np.ndarray:
        """``z [m]`` of a flattened observation ``[m]`` (non-finite entries count as 0)."""
        z = (np.asarray(observation, dtype=np.float64) - self.mean) / self.std
        return np.clip(np.nan_to_num(z, nan=0.0, posinf=FEEDBACK_CLIP, neginf=-FEEDBACK_CLIP),
                       -FEEDBACK_CLIP, FEEDBACK_CLIP)

    def __call__(self, gains: np.ndarray, observation: np.ndarray) -> np.ndarray:
        """``K z [n]`` for gains ``K [n, m]`` (action units per standard deviation) and an observation ``[m]``."""
        return gains @ self.features(observation)
