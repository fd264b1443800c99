"""Task-space control of the sponge: a joint-target plan from the path IK plus wrist-force adaptation.

The path is solved once (``ik.PathIK``); online, the only correction is the pressing depth along the
(nominal) table normal, which an admittance law adapts from the bias-corrected wrist force so that the
normal force tracks a target. A depth change maps to joints through the precomputed direction
``normal_dq`` (joint motion per metre along the normal at fixed sponge orientation), so the online
cost is a few vector operations per control step.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .ik import IKResult

__all__ = ["ForceAdaptation", "ForceAdaptationSettings", "JointTargetPlan"]


@dataclass(frozen=True)
class ForceAdaptationSettings:
    """Admittance law for the pressing depth.

    Attributes:
        target_force: normal force to hold while wiping (N).
        enabled: adapt the depth online; ``False`` keeps the feed-forward preload only.
        gain: depth rate per newton of force error (m / (N s)).
        max_rate: bound on the depth rate (m/s).
        min_offset, max_offset: bounds of the adapted depth offset (m; + = press deeper).
        stiffness: assumed contact stiffness (N/m) for the feed-forward preload ``target_force / stiffness``.
        filter_time: time constant of the first-order force filter (s).
        engage_height: the law acts only where the commanded path is below this height above the
            surface (m), fully at height <= 0 and fading linearly to nothing at ``engage_height``.
    """

    target_force: float = 18.0
    enabled: bool = True
    gain: float = 0.02
    max_rate: float = 0.08
    min_offset: float = -0.06
    max_offset: float = 0.08
    stiffness: float = 2500.0
    filter_time: float = 0.01
    engage_height: float = 0.02

    def __post_init__(self) -> None:
        for name in ("target_force", "stiffness", "max_rate", "engage_height"):
            if not np.isfinite(getattr(self, name)) or getattr(self, name) <= 0:
                raise ValueError(f"{name}: expected a finite positive number, got {getattr(self, name)!r}")
        if not (np.isfinite(self.gain) and self.gain >= 0):
            raise ValueError(f"gain: expected a finite number >= 0, got {self.gain!r}")
        if not self.min_offset <= 0.0 <= self.max_offset:
            raise ValueError("min_offset, max_offset: expected min_offset <= 0 <= max_offset")
        if self.filter_time < 0:
            raise ValueError("filter_time: expected a number >= 0")


class ForceAdaptation:
    """Stateful admittance controller: measured normal force -> pressing depth (m)."""

    def __init__(self, settings: ForceAdaptationSettings, dt: float):
        self.settings = settings
        self.dt = float(dt)
        self.preload = settings.target_force / settings.stiffness
        self.alpha = 1.0 if settings.filter_time == 0 else 1.0 - np.exp(-self.dt / settings.filter_time)
        self.reset()

    def reset(self) -> None:
        """Zero the adapted offset and the force filter."""
        self.offset = 0.0
        self.force = 0.0

    def update(self, force: float, path_height: float) -> float:
        """Feed one force measurement (N, + = pressing) and return the depth to command (m)."""
        s = self.settings
        self.force += self.alpha * (force - self.force)
        if s.enabled:
            engage = min(1.0, max(0.0, 1.0 - path_height / s.engage_height))
            rate = s.gain * (s.target_force - self.force) * engage
            rate = min(s.max_rate, max(-s.max_rate, rate))
            self.offset = min(s.max_offset, max(s.min_offset, self.offset + rate * self.dt))
        return self.preload + self.offset


class JointTargetPlan:
    """Servo targets of a solved path, shifted online by a pressing depth.

    A position servo ``kp (q_ref - q) - kv qdot`` lags a moving target by about ``kv / kp`` seconds;
    the plan adds the velocity feed-forward ``q_ref = q + (kv / kp) qdot_path`` so that the servo acts
    as a PD tracker of the path.

    Args:
        solution: IK of the path at zero depth, ``T`` points at the control rate.
        dt: control period (s).
        lead: ``kv / kp`` per joint [n] (s); zeros disable the feed-forward.
        lower, upper: joint limits [n] the targets are clipped to.
        normal: the surface normal [3] (world) the path was solved for (default +z); the pressing depth
            acts along it and the wrist force is measured along it.
    """

    def __init__(self, solution: IKResult, dt: float, lead: np.ndarray, lower: np.ndarray,
                 upper: np.ndarray, normal: np.ndarray | None = None):
        q = solution.q
        velocity = np.gradient(q, dt, axis=0) if len(q) > 1 else np.zeros_like(q)
        self.path_q = q
        self.velocity = velocity
        self.lead = np.asarray(lead, dtype=np.float64)
        self.dt = float(dt)
        self.q = q + self.lead * velocity
        self.normal_dq = solution.normal_dq
        self.lower = np.asarray(lower, dtype=np.float64)
        self.upper = np.asarray(upper, dtype=np.float64)
        normal = np.array([0.0, 0.0, 1.0]) if normal is None else np.asarray(normal, dtype=np.float64)
        self.normal = normal / np.linalg.norm(normal)

    def __len__(self) -> int:
        return len(self.q)

    def follow(self, start: int, q: np.ndarray, normal_dq: np.ndarray) -> None:
        """From control step ``start`` on, the targets follow the joint path ``q [T, n]`` (and the pressing direction
        ``normal_dq [T, n]``), in place: a simulation running along this plan takes the new targets from there. The
        steps before ``start`` (executed) keep theirs."""
        if q.shape != self.path_q.shape or normal_dq.shape != self.normal_dq.shape:
            raise ValueError(f"q, normal_dq: expected shape {self.path_q.shape}, got {q.shape} and {normal_dq.shape}")
        self.path_q[start:] = q[start:]
        self.normal_dq[start:] = normal_dq[start:]
        velocity = np.gradient(self.path_q, self.dt, axis=0) if len(q) > 1 else np.zeros_like(q)
        self.velocity[start:] = velocity[start:]
        self.q[start:] = self.path_q[start:] + self.lead * velocity[start:]

    def target(self, k: int, depth: float) -> np.ndarray:
        """Joint targets [n] at control step ``k`` with the sponge pressed ``depth`` metres along -normal."""
        return np.clip(self.q[k] - depth * self.normal_dq[k], self.lower, self.upper)
