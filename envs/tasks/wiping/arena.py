"""The wiping scene composed from parts: the arena (table, cup, floor, cameras), a robot and the sponge tool.

:func:`compose_scene` loads the arena, attaches the robot's MJCF at its base pose and the sponge tool at the
robot's tool mount with MuJoCo's ``MjSpec``, then adds the sensors the task reads, named by pattern: the wrist
force and torque at the robot's sensor site, the pad's touch sensor, the pad-table contact force, robot-table
contact, ``arm_<link>`` for the arm touching each link of the robot's own body, and ``arm_obstacle``.
"""

from __future__ import annotations

from pathlib import Path

import mujoco

from ...arena import DIST, FORCE, FOUND, MINDIST, NETFORCE, add_contact_sensor, self_contact_sensors
from ...robots import RobotDescription

__all__ = ["ARENA_XML", "SPONGE_XML", "add_task", "compose_scene"]

ASSETS = Path(__file__).resolve().parents[2] / "assets"
ARENA_XML = ASSETS / "arena.xml"
SPONGE_XML = ASSETS / "sponge_tool.xml"


def _add_sensors(spec: mujoco.MjSpec, robot: RobotDescription, prefix: str, tool: str) -> None:
    site, geom = mujoco.mjtObj.mjOBJ_SITE, mujoco.mjtObj.mjOBJ_GEOM
    subtree, body = mujoco.mjtObj.mjOBJ_XBODY, mujoco.mjtObj.mjOBJ_BODY
    ft_site = prefix + robot.ft_site
    spec.add_sensor(name="wrist_force", type=mujoco.mjtSensor.mjSENS_FORCE, objtype=site, objname=ft_site)
    spec.add_sensor(name="wrist_torque", type=mujoco.mjtSensor.mjSENS_TORQUE, objtype=site, objname=ft_site)
    spec.add_sensor(name="sponge_touch", type=mujoco.mjtSensor.mjSENS_TOUCH, objtype=site,
                    objname=tool + "sponge_touch")
    add_contact_sensor(spec, "sponge_table", (geom, tool + "sponge"), (geom, "table_top"), FOUND | FORCE, NETFORCE)
    add_contact_sensor(spec, "robot_table", (subtree, prefix + robot.root_body), (geom, "table_top"), FOUND)
    arm = (subtree, prefix + robot.arm_root)
    for name, link in zip(self_contact_sensors(robot), robot.body_links, strict=True):
        add_contact_sensor(spec, name, arm, (body, prefix + link), FOUND | DIST, MINDIST)
    add_contact_sensor(spec, "arm_obstacle", arm, (body, "obstacle"), FOUND)


def compose_scene(robot: RobotDescription, prefix: str = "robot/", tool: str = "tool/") -> mujoco.MjModel:
    """The compiled scene: the arena with ``robot`` at its base pose, the sponge on its tool mount, the sensors.

    The robot's names get ``prefix``, the sponge tool's ``tool`` (the arena's and the sensors' none). Raises
    ValueError naming the description's field when the robot's MJCF lacks a body, site, joint or geom it names.
    """
    if not prefix or not tool or prefix == tool:
        raise ValueError("prefix, tool: expected two different non-empty name prefixes")
    spec = mujoco.MjSpec.from_file(str(ARENA_XML))
    robot_spec = robot.spec()
    _check_names(robot_spec, robot)
    frame = spec.worldbody.add_frame(pos=list(robot.base_pos), quat=list(robot.base_quat))
    spec.attach(robot_spec, frame=frame, prefix=prefix)
    add_task(spec, robot, prefix, tool)
    return spec.compile()


def add_task(spec: mujoco.MjSpec, robot: RobotDescription, prefix: str, tool: str) -> None:
    """Add the wiping task to a scene ``spec`` that has the arena and ``robot`` (names prefixed ``prefix``): the sponge
    tool on the robot's tool mount (names prefixed ``tool``) and the sensors (see the module docstring)."""
    mount = spec.body(prefix + robot.tool_mount.body).add_frame(pos=list(robot.tool_mount.pos),
                                                               quat=list(robot.tool_mount.quat))
    spec.attach(mujoco.MjSpec.from_file(str(SPONGE_XML)), frame=mount, prefix=tool)
    _add_sensors(spec, robot, prefix, tool)


def _check_names(spec: mujoco.MjSpec, robot: RobotDescription) -> None:
    """ValueError naming the field of ``robot`` whose body, site, joint or geom its MJCF lacks."""
    wanted = dict(root_body=(spec.body, [robot.root_body]), arm_root=(spec.body, [robot.arm_root]),
                  body_links=(spec.body, list(robot.body_links)), tool_mount=(spec.body, [robot.tool_mount.body]),
                  ft_site=(spec.site, [robot.ft_site]), joints=(spec.joint, list(robot.joints)),
                  hand_geoms=(spec.geom, list(robot.hand_geoms)))
    for field, (find, names) in wanted.items():
        missing = [n for n in names if find(n) is None]
        if missing:
            raise ValueError(f"{field}: the MJCF of the robot {robot.name!r} has no {missing}")
