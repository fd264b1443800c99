"""The wiping task's objects in a compiled scene: where they are (:class:`WipeParts`), how the context places them
(the table pose, the cup) and the dirt grid.

Frames: the *table frame* has its origin on the table's top surface, x forward, y left, z along the
surface normal. The *nominal* table frame is the one the demonstration and the controller assume
(the table body's pose as compiled); the *actual* frame includes the episode's height offset and tilt.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from ...arena import self_contact_sensors
from ...robots import RobotDescription
from ...task_scene import rotation_from_tilt
from .context import Context

__all__ = ["OBSTACLE_PARKING", "TablePose", "WipeParts", "control_frame", "dirt_grid", "place_objects",
           "table_frame", "to_world", "wrist_force_world"]

#: Where a parked (absent) obstacle waits: under the floor, out of sight, weightless, with its collisions off.
OBSTACLE_PARKING = np.array([0.2, 1.5, -1.0])
#: the sensors the wiping task reads (beside the robot's own ``robot_table`` and ``arm_<link>``)
TASK_SENSORS = ("wrist_force", "wrist_torque", "sponge_touch", "sponge_table", "arm_obstacle")


@dataclass(frozen=True)
class TablePose:
    """Deviation of the actual table from the nominal one.

    Attributes:
        height: offset of the surface along the world z axis (metres, + = higher).
        tilt_x: rotation about the table frame's x axis (radians, + raises the right side, -y).
        tilt_y: rotation about the table frame's y axis (radians, + lowers the far side, +x).
    """

    height: float = 0.0
    tilt_x: float = 0.0
    tilt_y: float = 0.0

    @classmethod
    def of(cls, context: Context) -> TablePose:
        """The table pose of ``context``."""
        return cls(context.table_height, *context.table_tilt)


def dirt_grid(centre: np.ndarray, size: np.ndarray, cell: float) -> np.ndarray:
    """Centres [N, 2] (table frame, metres) of a grid of square cells of side ``cell`` over a patch.

    The patch is ``size`` = (sx, sy) around ``centre`` = (cx, cy); the number of cells per side is
    ``max(1, round(s / cell))``, so the cells tile the patch exactly (their side may differ slightly
    from ``cell``).
    """
    centre = np.asarray(centre, dtype=np.float64)
    size = np.asarray(size, dtype=np.float64)
    if centre.shape != (2,) or size.shape != (2,):
        raise ValueError("centre, size: expected two numbers each")
    if cell <= 0 or np.any(size <= 0):
        raise ValueError("cell, size: expected positive numbers")
    counts = np.maximum(1, np.round(size / cell).astype(int))
    axes = [centre[i] - size[i] / 2 + (np.arange(counts[i]) + 0.5) * size[i] / counts[i] for i in range(2)]
    gx, gy = np.meshgrid(axes[0], axes[1], indexing="ij")
    return np.stack([gx.ravel(), gy.ravel()], axis=1)


@dataclass(frozen=True)
class WipeParts:
    """Where the wiping task's objects and sensors are in a compiled scene, read by :meth:`read` from the model as
    compiled (before :func:`place_objects` moves the table and the cup).

    Attributes:
        table_body, table_geom: the table's body and its top's box geom.
        table_origin, table_rotation: the nominal table frame in the world (``[3]``, ``[3, 3]``).
        table_extent: the table top in the table frame, (x_low, x_high, y_low, y_high) (m).
        sponge_geom, sponge_site: the sponge's box geom and its face centre's site (the tool's tip).
        sponge_half: the sponge box's half sizes ``[3]`` (its face is the -x side).
        ft_site: the robot's wrist force-torque site.
        obstacle_body, obstacle_geom: the cup (a free body with a cylinder geom).
        obstacle_qpos: the first of the cup's free joint's 7 ``qpos`` entries.
        obstacle_radius, obstacle_half_height: the cup's cylinder (m).
        obstacle_collision: the cup geom's ``(contype, conaffinity)`` where it stands on the table.
        force_adr: the wrist force's columns of ``data.sensordata`` (3).
        sponge_contact_adr: the sponge-table contact sensor's first column (found, net force [3], world frame).
        robot_contact_adr: the robot-table contact sensor's column (found).
        self_contact_adr: per link of the robot's own body, the first column of the arm's contact sensor with it
            (found, distance).
        obstacle_contact_adr: the arm-cup contact sensor's column (found).
        is_arm_geom: ``[ngeom]`` the robot's geoms but the sponge (what counts as an arm collision with the table).
    """

    table_body: int
    table_geom: int
    table_origin: np.ndarray
    table_rotation: np.ndarray
    table_extent: tuple[float, float, float, float]
    sponge_geom: int
    sponge_site: int
    sponge_half: np.ndarray
    ft_site: int
    obstacle_body: int
    obstacle_geom: int
    obstacle_qpos: int
    obstacle_radius: float
    obstacle_half_height: float
    obstacle_collision: tuple[int, int]
    force_adr: slice
    sponge_contact_adr: int
    robot_contact_adr: int
    self_contact_adr: tuple[int, ...]
    obstacle_contact_adr: int
    is_arm_geom: np.ndarray

    @classmethod
    def read(cls, model: mujoco.MjModel, robot: RobotDescription, robot_prefix: str = "", tool_prefix: str = "",
             source: str = "the composed scene") -> WipeParts:
        """The parts in ``model`` (the robot's names prefixed ``robot_prefix``, the sponge tool's ``tool_prefix``, the
        arena's and the sensors' none); ValueError naming ``xml_file`` and what ``source`` lacks."""
        names = _Names(model, robot_prefix, tool_prefix)
        _check(names, robot, source)
        body, geom, site = mujoco.mjtObj.mjOBJ_BODY, mujoco.mjtObj.mjOBJ_GEOM, mujoco.mjtObj.mjOBJ_SITE
        table_body, table_geom = names.id(body, "arena", "table"), names.id(geom, "arena", "table_top")
        obstacle_geom = names.id(geom, "arena", "obstacle")
        free = names.id(mujoco.mjtObj.mjOBJ_JOINT, "arena", "obstacle_free")
        if (model.jnt_type[free] != mujoco.mjtJoint.mjJNT_FREE
                or model.geom_type[obstacle_geom] != mujoco.mjtGeom.mjGEOM_CYLINDER):
            raise ValueError("xml_file: 'obstacle_free' must be a free joint and geom 'obstacle' a cylinder")
        sensor = _sensor_columns(model)
        if model.sensor_dim[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SENSOR, "sponge_table")] != 4:
            raise ValueError("xml_file: sensor 'sponge_table' must be a contact sensor with data=\"found force\" "
                             "and reduce=\"netforce\"")
        rotation = np.zeros(9)
        mujoco.mju_quat2Mat(rotation, model.body_quat[table_body])
        top, half = model.geom_pos[table_geom], model.geom_size[table_geom]
        sponge_geom = names.id(geom, "tool", "sponge")
        return cls(table_body=table_body, table_geom=table_geom, table_origin=model.body_pos[table_body].copy(),
                   table_rotation=rotation.reshape(3, 3),
                   table_extent=(float(top[0] - half[0]), float(top[0] + half[0]), float(top[1] - half[1]),
                                 float(top[1] + half[1])),
                   sponge_geom=sponge_geom, sponge_site=names.id(site, "tool", "sponge_tcp"),
                   sponge_half=model.geom_size[sponge_geom].copy(), ft_site=names.id(site, "robot", robot.ft_site),
                   obstacle_body=names.id(body, "arena", "obstacle"), obstacle_geom=obstacle_geom,
                   obstacle_qpos=int(model.jnt_qposadr[free]),
                   obstacle_radius=float(model.geom_size[obstacle_geom, 0]),
                   obstacle_half_height=float(model.geom_size[obstacle_geom, 1]),
                   obstacle_collision=(int(model.geom_contype[obstacle_geom]),
                                       int(model.geom_conaffinity[obstacle_geom])),
                   force_adr=slice(sensor["wrist_force"], sensor["wrist_force"] + 3),
                   sponge_contact_adr=sensor["sponge_table"], robot_contact_adr=sensor["robot_table"],
                   self_contact_adr=tuple(sensor[n] for n in self_contact_sensors(robot)),
                   obstacle_contact_adr=sensor["arm_obstacle"],
                   is_arm_geom=_arm_geoms(model, names.id(body, "robot", robot.root_body), sponge_geom))


@dataclass(frozen=True)
class _Names:
    """The model's names of the robot's, the sponge tool's and the arena's objects."""

    model: mujoco.MjModel
    robot_prefix: str
    tool_prefix: str

    def id(self, obj: mujoco.mjtObj, part: str, name: str) -> int:
        """The model id of object ``name`` of ``part`` (``"robot"``, ``"tool"`` or ``"arena"``; -1 if none)."""
        prefix = {"robot": self.robot_prefix, "tool": self.tool_prefix}.get(part, "")
        return mujoco.mj_name2id(self.model, obj, prefix + name)


def _check(names: _Names, robot: RobotDescription, source: str) -> None:
    """ValueError naming ``xml_file`` and what ``source`` lacks."""
    body, geom, site = mujoco.mjtObj.mjOBJ_BODY, mujoco.mjtObj.mjOBJ_GEOM, mujoco.mjtObj.mjOBJ_SITE
    joint, sensor = mujoco.mjtObj.mjOBJ_JOINT, mujoco.mjtObj.mjOBJ_SENSOR
    sensors = ("robot_table", *self_contact_sensors(robot), *TASK_SENSORS)
    required = [(body, "arena", ("table", "obstacle")), (geom, "arena", ("table_top", "obstacle")),
                (body, "robot", (robot.root_body, robot.arm_root, *robot.body_links)),
                (site, "robot", (robot.ft_site,)), (geom, "robot", robot.hand_geoms), (joint, "robot", robot.joints),
                (body, "tool", ("sponge",)), (geom, "tool", ("sponge",)), (site, "tool", ("sponge_tcp",)),
                (joint, "tool", ("sponge_slide",)), (joint, "arena", ("obstacle_free",)), (sensor, "arena", sensors)]
    for obj, part, wanted in required:
        missing = [n for n in wanted if names.id(obj, part, n) < 0]
        if missing:
            raise ValueError(f"xml_file: {source} lacks the required {obj.name[6:].lower()}(s) {missing}")


def _sensor_columns(model: mujoco.MjModel) -> dict[str, int]:
    """Sensor name -> its first column of ``data.sensordata``."""
    return {model.sensor(i).name: int(model.sensor_adr[i]) for i in range(model.nsensor)}


def _arm_geoms(model: mujoco.MjModel, root: int, sponge_geom: int) -> np.ndarray:
    """``[ngeom]`` the geoms of the bodies in ``root``'s subtree but the sponge."""
    def descends(b: int) -> bool:
        while b > 0:
            if b == root:
                return True
            b = int(model.body_parentid[b])
        return False

    robot_bodies = {b for b in range(model.nbody) if descends(b)}
    arm = np.array([int(model.geom_bodyid[g]) in robot_bodies for g in range(model.ngeom)])
    arm[sponge_geom] = False
    return arm


def table_frame(parts: WipeParts, pose: TablePose) -> tuple[np.ndarray, np.ndarray]:
    """(origin [3], rotation [3, 3]) of the actual table frame in the world for the table ``pose``."""
    origin = parts.table_origin + np.array([0.0, 0.0, pose.height])
    return origin, parts.table_rotation @ rotation_from_tilt(pose.tilt_x, pose.tilt_y)


def control_frame(parts: WipeParts, pose: TablePose) -> tuple[np.ndarray, np.ndarray]:
    """(origin [3], rotation [3, 3]) of the frame the controller plans in: the nominal table origin (the height offset
    is unknown to the controller and found by the force adaptation) with the actual table orientation (the tilt is in
    the context, so the sponge follows the actual normal)."""
    return parts.table_origin.copy(), table_frame(parts, pose)[1]


def to_world(parts: WipeParts, pose: TablePose, points: np.ndarray) -> np.ndarray:
    """Table-frame points ``[..., 3]`` to world points ``[..., 3]`` in the control frame (:func:`control_frame`)."""
    origin, rot = control_frame(parts, pose)
    return np.asarray(points, dtype=np.float64) @ rot.T + origin


def place_objects(model: mujoco.MjModel, parts: WipeParts, context: Context) -> None:
    """Move the table to the context's pose and stand the cup upright on it at the context's position, or park it out
    of the scene (weightless, no collisions) without one: the cup's rest pose is its free joint's ``qpos0``, where
    the next reset of the data puts it."""
    pose = TablePose.of(context)
    origin, rot = table_frame(parts, pose)
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, rot.ravel())
    model.body_pos[parts.table_body] = origin
    model.body_quat[parts.table_body] = quat
    body, geom, adr = parts.obstacle_body, parts.obstacle_geom, parts.obstacle_qpos
    if not context.obstacle:
        model.body_gravcomp[body] = 1.0
        model.geom_contype[geom] = 0
        model.geom_conaffinity[geom] = 0
        model.qpos0[adr:adr + 7] = np.r_[OBSTACLE_PARKING, 1.0, 0.0, 0.0, 0.0]
        return
    model.body_gravcomp[body] = 0.0
    model.geom_contype[geom], model.geom_conaffinity[geom] = parts.obstacle_collision
    centre = origin + rot @ np.r_[context.obstacle_position, parts.obstacle_half_height + 1e-4]
    model.qpos0[adr:adr + 7] = np.r_[centre, quat]


def wrist_force_world(data: mujoco.MjData, parts: WipeParts) -> np.ndarray:
    """The raw wrist force sensor reading rotated into the world frame ``[3]`` (N)."""
    rot = data.site_xmat[parts.ft_site].reshape(3, 3)
    return rot @ data.sensordata[parts.force_adr]
