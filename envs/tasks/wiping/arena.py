"""The wiping task's part of a scene: the arena (the room and the cup) and the sponge tool with the task's sensors.

:data:`ARENA_XML` is the room the task's scene starts from (the standard room, ``room.xml``: floor, light, cameras,
table; and the cup). :func:`add_task` attaches the sponge tool at the robot's tool mount with MuJoCo's ``MjSpec``
and adds the sensors the task reads, named by pattern: the wrist force and torque at the robot's sensor site, the
pad's touch sensor, the pad-table contact force and ``arm_obstacle`` (the scene adds ``robot_table`` and
``arm_<link>``, :mod:`rdmp_gym.envs.task_scene`).
"""

from __future__ import annotations

from pathlib import Path

import mujoco

from ...arena import FORCE, FOUND, NETFORCE, add_contact_sensor
from ...robots import RobotDescription

__all__ = ["ARENA_XML", "SPONGE_XML", "add_task"]

ASSETS = Path(__file__).resolve().parents[2] / "assets"
ARENA_XML = ASSETS / "arena.xml"
SPONGE_XML = ASSETS / "sponge_tool.xml"


def add_task(spec: mujoco.MjSpec, robot: RobotDescription, prefix: str, tool: str) -> None:
    """Add the wiping task to a scene ``spec`` that has the arena and ``robot`` (names prefixed ``prefix``): the sponge
    tool on the robot's tool mount (names prefixed ``tool``) and the sensors (see the module docstring). Raises
    ValueError naming the description's field when the robot's MJCF lacks a body, site, joint or geom it names."""
    _check_names(spec, robot, prefix)
    mount = spec.body(prefix + robot.tool_mount.body).add_frame(pos=list(robot.tool_mount.pos),
                                                               quat=list(robot.tool_mount.quat))
    spec.attach(mujoco.MjSpec.from_file(str(SPONGE_XML)), frame=mount, prefix=tool)
    _add_sensors(spec, robot, prefix, tool)


def _add_sensors(spec: mujoco.MjSpec, robot: RobotDescription, prefix: str, tool: str) -> None:
    site, geom = mujoco.mjtObj.mjOBJ_SITE, mujoco.mjtObj.mjOBJ_GEOM
    ft_site = prefix + robot.ft_site
    spec.add_sensor(name="wrist_force", type=mujoco.mjtSensor.mjSENS_FORCE, objtype=site, objname=ft_site)
    spec.add_sensor(name="wrist_torque", type=mujoco.mjtSensor.mjSENS_TORQUE, objtype=site, objname=ft_site)
    spec.add_sensor(name="sponge_touch", type=mujoco.mjtSensor.mjSENS_TOUCH, objtype=site,
                    objname=tool + "sponge_touch")
    add_contact_sensor(spec, "sponge_table", (geom, tool + "sponge"), (geom, "table_top"), FOUND | FORCE, NETFORCE)
    add_contact_sensor(spec, "arm_obstacle", (mujoco.mjtObj.mjOBJ_XBODY, prefix + robot.arm_root),
                       (mujoco.mjtObj.mjOBJ_BODY, "obstacle"), FOUND)


def _check_names(spec: mujoco.MjSpec, robot: RobotDescription, prefix: str) -> None:
    """ValueError naming the field of ``robot`` whose body, site, joint or geom the attached MJCF lacks."""
    wanted = dict(root_body=(spec.body, [robot.root_body]), arm_root=(spec.body, [robot.arm_root]),
                  body_links=(spec.body, list(robot.body_links)), tool_mount=(spec.body, [robot.tool_mount.body]),
                  ft_site=(spec.site, [robot.ft_site]), joints=(spec.joint, list(robot.joints)),
                  hand_geoms=(spec.geom, list(robot.hand_geoms)))
    for field, (find, names) in wanted.items():
        missing = [n for n in names if find(prefix + n) is None]
        if missing:
            raise ValueError(f"{field}: the MJCF of the robot {robot.name!r} has no {missing}")
