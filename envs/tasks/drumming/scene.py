"""The drumming task's objects: a stick in the robot's hand, a drum with a rim, and the sensors that hear them.

- The **stick** hangs on the robot's tool mount (whose -x axis points out of the hand): a shaft of ``STICK_LENGTH``
  along -x and a round tip, held in a sprung, damped grip that gives way along the stick (up to 15 mm, 1500 N/m),
  as a drummer's loose hold does: a stroke that goes too deep presses, it does not crush. The site ``tip`` (on the
  hand, at the resting tip's lowest point) is what the inverse kinematics places on the path, with the stick's
  axis along the drum's.
- The **drum** (a static body that ``reset`` moves: its frame is the membrane's centre, z along the drum's axis):
  a membrane of radius ``MEMBRANE_RADIUS`` (a stiff, lightly damped contact: the stick bounces off), the shell
  under it, a rim of capsules standing ``RIM_HEIGHT`` above the membrane's edge, and a stand down to the table.
- **Sensors**: ``drum_hit`` (the tip on the membrane: contacts found and their net force, read at every physics step
  as the strike's force), ``robot_drum`` (any robot geom, the stick included, on any part of the drum: contacts
  found), ``robot_rim`` (any robot geom on the rim).
"""

from __future__ import annotations

import mujoco
import numpy as np

from ...arena import FORCE, FOUND, NETFORCE, add_contact_sensor
from ...robots import RobotDescription
from ...task_scene import rotation_from_tilt

__all__ = ["DRUM_PREFIX", "MEMBRANE_RADIUS", "RIM_HEIGHT", "STICK_LENGTH", "add_drum", "add_stick", "place_drum"]

STICK_LENGTH = 0.12
MEMBRANE_RADIUS = 0.10
RIM_HEIGHT = 0.006
#: the drum's names in the scene start with this
DRUM_PREFIX = "drum/"
_RIM_PIECES = 16
_SHELL_DEPTH = 0.08

_STICK = f"""
<mujoco model="stick">
  <worldbody>
    <body name="stick" gravcomp="1">
      <joint name="grip" type="slide" axis="1 0 0" stiffness="1500" damping="10" armature="0.01"
             range="-0.001 0.015"/>
      <inertial pos="-{STICK_LENGTH / 2} 0 0" mass="0.05" diaginertia="6e-5 6e-5 2e-6"/>
      <geom name="shaft" type="capsule" fromto="0 0 0 -{STICK_LENGTH - 0.012} 0 0" size="0.007" contype="6"
            conaffinity="1" rgba="0.85 0.70 0.45 1"/>
      <geom name="tip" type="sphere" pos="-{STICK_LENGTH} 0 0" size="0.012" contype="6" conaffinity="1"
            rgba="0.95 0.90 0.80 1"/>
    </body>
    <site name="tip" pos="-{STICK_LENGTH + 0.012} 0 0" size="0.004" group="4"/>
  </worldbody>
</mujoco>
"""


def _drum_xml() -> str:
    angles = 2.0 * np.pi * np.arange(_RIM_PIECES) / _RIM_PIECES
    radius = MEMBRANE_RADIUS + 0.004
    ends = np.stack([radius * np.cos(angles), radius * np.sin(angles)], axis=1)
    pieces = "".join(
        f'<geom name="rim_{i}" type="capsule" size="0.006" fromto="{a[0]:.5f} {a[1]:.5f} {RIM_HEIGHT - 0.006} '
        f'{b[0]:.5f} {b[1]:.5f} {RIM_HEIGHT - 0.006}" contype="1" conaffinity="2" rgba="0.75 0.75 0.78 1"/>'
        for i, (a, b) in enumerate(zip(ends, np.roll(ends, -1, axis=0), strict=True)))
    return f"""
<mujoco model="drum">
  <worldbody>
    <body name="body" pos="0.6 -0.28 1.0">
      <geom name="membrane" type="cylinder" size="{MEMBRANE_RADIUS} 0.003" pos="0 0 -0.003" contype="1"
            conaffinity="2" solref="0.004 0.3" solimp="0.9 0.95 0.002" friction="0.3 0.005 0.0001"
            rgba="0.96 0.94 0.86 1"/>
      <geom name="shell" type="cylinder" size="{MEMBRANE_RADIUS + 0.003} {_SHELL_DEPTH / 2}"
            pos="0 0 -{_SHELL_DEPTH / 2 + 0.006}" contype="1" conaffinity="2" rgba="0.62 0.10 0.12 1"/>
      <geom name="stand" type="cylinder" size="0.012 0.1" pos="0 0 -0.2" contype="0" conaffinity="0"
            rgba="0.3 0.3 0.3 1"/>
      <body name="rim">{pieces}</body>
    </body>
  </worldbody>
</mujoco>
"""


def add_stick(spec: mujoco.MjSpec, robot: RobotDescription, robot_prefix: str, tool_prefix: str) -> None:
    """Attach the stick to ``robot``'s tool mount (names prefixed ``tool_prefix``)."""
    mount = robot.tool_mount
    frame = spec.body(robot_prefix + mount.body).add_frame(pos=list(mount.pos), quat=list(mount.quat))
    spec.attach(mujoco.MjSpec.from_string(_STICK), frame=frame, prefix=tool_prefix)


def add_drum(spec: mujoco.MjSpec, robot: RobotDescription, robot_prefix: str, tool_prefix: str) -> None:
    """Add the drum to the room and the drumming sensors (see the module docstring)."""
    drum = mujoco.MjSpec.from_string(_drum_xml())
    spec.attach(drum, frame=spec.worldbody.add_frame(), prefix=DRUM_PREFIX)
    geom, subtree = mujoco.mjtObj.mjOBJ_GEOM, mujoco.mjtObj.mjOBJ_XBODY
    add_contact_sensor(spec, "drum_hit", (geom, tool_prefix + "tip"), (geom, DRUM_PREFIX + "membrane"),
                       FOUND | FORCE, NETFORCE)
    root = (subtree, robot_prefix + robot.root_body)
    add_contact_sensor(spec, "robot_drum", root, (subtree, DRUM_PREFIX + "body"), FOUND)
    add_contact_sensor(spec, "robot_rim", root, (subtree, DRUM_PREFIX + "rim"), FOUND)


def place_drum(model: mujoco.MjModel, centre: np.ndarray, tilt: np.ndarray, height: float) -> None:
    """Move the drum: its membrane's centre to ``centre [3]`` (world), its axis tilted by ``tilt`` (roll, pitch; rad,
    as a table tilt), its stand reaching ``height`` (m) down to the table."""
    body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, DRUM_PREFIX + "body")
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, rotation_from_tilt(*tilt).ravel())
    model.body_pos[body] = centre
    model.body_quat[body] = quat
    stand = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, DRUM_PREFIX + "stand")
    length = max(0.5 * (height - _SHELL_DEPTH - 0.006), 0.005)
    model.geom_size[stand, 1] = length
    model.geom_pos[stand, 2] = -(_SHELL_DEPTH + 0.006 + length)
