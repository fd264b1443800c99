"""What the wiping task knows of a robot: one :class:`RobotDescription` per arm.

A description names the robot's MJCF (the robot alone: bodies, joints, position servos), its controlled joints
in chain order, where the sponge tool is mounted, the wrist force-sensor site, the geoms that the cup and
self-collision checks use, the posture the inverse kinematics prefers, the joint limits the task holds it to
and the box of the table frame it can reach. :mod:`rdmp_gym.envs.task_scene` and the wiping task's
:mod:`rdmp_gym.envs.tasks.wiping.arena` compose the scene from it; no other module names a robot's bodies or joints.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import mujoco
import numpy as np

__all__ = ["BodyClearanceGeoms", "RobotDescription", "ToolMount"]


@dataclass(frozen=True)
class ToolMount:
    """Where the sponge tool hangs: a frame on ``body`` at ``pos [3]`` (m) and ``quat [4]`` (w, x, y, z), in which
    +x points away from the pad's face (the face normal is -x) and the face centre is 2 cm along -x."""

    body: str
    pos: tuple[float, float, float] = (0.0, 0.0, 0.0)
    quat: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)


@dataclass(frozen=True)
class BodyClearanceGeoms:
    """Geoms for the inverse kinematics' clearance of the arm from the robot's body: a box geom ``box`` on body
    ``box_body`` and capsule geoms ``capsules`` on the bodies ``capsule_bodies`` (one each, same order)."""

    box_body: str
    box: str
    capsule_bodies: tuple[str, ...]
    capsules: tuple[str, ...]


@dataclass(frozen=True)
class RobotDescription:
    """One robot arm for the wiping task.

    Attributes:
        name: registry key (``"armar3"``, ``"panda"``, ...).
        spec: returns a fresh ``mujoco.MjSpec`` of the robot alone (no world, table, sponge or sensors): bodies,
            joints with their ranges and a position actuator (``ctrllimited``) per controlled joint.
        joints: the controlled joints in chain order (base to tool).
        root_body: the robot's root body: every geom in its subtree is the robot's.
        arm_root: the first body of the moving arm: the subtree whose contacts with the robot's body, the cup and
            the table are collisions.
        body_links: bodies of the robot's own body (torso, platform, base) that the moving arm must not touch.
        tool_mount: where the sponge tool is attached.
        ft_site: the wrist force/torque sensor's site (on a body whose subtree is the hand and the sponge).
        hand_geoms: geoms of the hand that the cup-clearance term keeps away from the cup (the sponge is added).
        posture: ``[n]`` preferred joint positions of the inverse kinematics (the wiping posture, well inside the
            limits), ``n = len(joints)``.
        mobility: ``[n]`` relative mobility of the joints in the inverse kinematics (small: moves little).
        max_joint_speed: joint speed (rad/s) beyond which a planned path is not executable.
        max_joint_accel: joint acceleration (rad/s²) beyond which the motion is not executable.
        workspace: ``(low [3], high [3])``: the box of the nominal table frame the sponge may be commanded in.
        base_pos, base_quat: the robot's root pose in the world (the table's top is at z = 0.90 m, its frame at
            x = 0.52 m, y = -0.28 m).
        body_clearance: the inverse kinematics' arm-from-body clearance, or None without one.
        legacy_scene: a hand-merged scene MJCF that the task versions published before the composed scenes keep
            using (bit-identical returns), or None.
        joint_labels: short labels of the joints for plots and tables (default: the joint names).
    """

    name: str
    spec: Callable[[], mujoco.MjSpec]
    joints: tuple[str, ...]
    root_body: str
    arm_root: str
    body_links: tuple[str, ...]
    tool_mount: ToolMount
    ft_site: str
    hand_geoms: tuple[str, ...]
    posture: np.ndarray
    mobility: np.ndarray
    max_joint_speed: float
    max_joint_accel: float
    workspace: tuple[np.ndarray, np.ndarray]
    base_pos: tuple[float, float, float] = (0.0, 0.0, 0.0)
    base_quat: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)
    body_clearance: BodyClearanceGeoms | None = None
    legacy_scene: str | None = None
    joint_labels: tuple[str, ...] = field(default=())

    def __post_init__(self) -> None:
        n = len(self.joints)
        if n < 3 or len(set(self.joints)) != n:
            raise ValueError(f"joints: expected at least 3 distinct joint names, got {self.joints!r}")
        for name in ("posture", "mobility"):
            value = np.asarray(getattr(self, name), dtype=np.float64)
            if value.shape != (n,) or not np.all(np.isfinite(value)):
                raise ValueError(f"{name}: expected {n} finite numbers (one per joint), got shape {value.shape}")
            object.__setattr__(self, name, value)
        if np.any(self.mobility <= 0):
            raise ValueError("mobility: expected positive numbers")
        for name in ("max_joint_speed", "max_joint_accel"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"{name}: expected a positive number, got {value!r}")
        low, high = (np.asarray(v, dtype=np.float64) for v in self.workspace)
        if low.shape != (3,) or high.shape != (3,) or not np.all(low < high):
            raise ValueError(f"workspace: expected (low [3], high [3]) with low < high, got {self.workspace!r}")
        object.__setattr__(self, "workspace", (low, high))
        if self.joint_labels and len(self.joint_labels) != n:
            raise ValueError(f"joint_labels: expected {n} labels, got {len(self.joint_labels)}")
