"""Contact sensors of a scene, named by pattern: what every task adds to the room through MuJoCo's ``MjSpec``.

:func:`add_contact_sensor` adds one contact sensor between two objects (the data fields and the reduction as
MuJoCo's bits); :func:`self_contact_sensors` names the sensors of the moving arm touching each link of the robot's
own body (``arm_<link>``).
"""

from __future__ import annotations

import mujoco

from .robots import RobotDescription

__all__ = ["DIST", "FORCE", "FOUND", "MINDIST", "NETFORCE", "add_contact_sensor", "self_contact_sensors"]

# contact sensor settings (MuJoCo's intprm of a contact sensor: data fields as bits, reduction, number)
FOUND, FORCE, DIST = 1, 2, 8
MINDIST, NETFORCE = 1, 3


def self_contact_sensors(robot: RobotDescription) -> tuple[str, ...]:
    """Names of the sensors of the arm touching the robot's own body, one per link of ``robot.body_links``."""
    return tuple(f"arm_{link}" for link in robot.body_links)


def add_contact_sensor(spec: mujoco.MjSpec, name: str, first: tuple[mujoco.mjtObj, str],
                       second: tuple[mujoco.mjtObj, str], data: int, reduce: int = 0) -> None:
    """Add a contact sensor ``name`` between ``first`` and ``second`` (``(object type, name)`` each) reporting the
    ``data`` fields (bits: found 1, force 2, distance 8) reduced by ``reduce`` (min distance 1, net force 3)."""
    sensor = spec.add_sensor(name=name, type=mujoco.mjtSensor.mjSENS_CONTACT, objtype=first[0], objname=first[1],
                             reftype=second[0], refname=second[1])
    sensor.intprm[:3] = [data, reduce, 1]
