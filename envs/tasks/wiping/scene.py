"""The wiping scene: model loading, named indices, table pose (height offset, tilt) and the dirt grid.

Frames: the *table frame* has its origin on the table's top surface, x forward, y left, z along the
surface normal. The *nominal* table frame is the one the demonstration and the controller assume
(the table body's pose in the XML); the *actual* frame includes the episode's height offset and tilt.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from ...arena import self_contact_sensors
from ...robots import ARMAR3, RobotDescription, get_robot
from ...task_scene import read_arm, rotation_from_tilt, servo_lead
from .arena import compose_scene

__all__ = [
    "DEFAULT_XML",
    "TablePose",
    "WipeScene",
    "dirt_grid",
    "read_arm",
    "servo_lead",
]

logger = logging.getLogger(__name__)

#: The packaged ARMAR-III scene that ``ArmarWipe-v1`` and ``-v2`` were published with.
DEFAULT_XML = Path(ARMAR3.legacy_scene)
#: Prefixes of the robot's and the sponge tool's names in a composed scene (a hand-merged scene has none).
ROBOT_PREFIX, TOOL_PREFIX = "robot/", "tool/"

#: Where a parked (absent) obstacle waits: under the floor, out of sight, weightless, with its collisions off.
OBSTACLE_PARKING = np.array([0.2, 1.5, -1.0])


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


class WipeScene:
    """The MuJoCo model and data of the wiping scene, with the indices the controller needs.

    Args:
        robot: the robot (a registered name or a :class:`~rdmp_gym.envs.robots.RobotDescription`).
        composed: compose the scene from the arena, the robot and the sponge tool
            (:func:`~rdmp_gym.envs.tasks.wiping.arena.compose_scene`); ``False`` loads the robot's hand-merged
            ``legacy_scene``
            (the scene the task versions 1 and 2 were published with).
        xml_file: a hand-merged scene MJCF instead (with the names of the robot's description, the arena's and
            the sponge tool's, and the sensors of :mod:`~rdmp_gym.envs.tasks.wiping.arena`); excludes ``composed``.
    """

    def __init__(self, robot: str | RobotDescription = "armar3", composed: bool = False,
                 xml_file: str | Path | None = None):
        self.robot = get_robot(robot)
        if xml_file is not None and composed:
            raise ValueError("xml_file: give either xml_file or composed=True, not both")
        if xml_file is None and not composed and self.robot.legacy_scene is None:
            raise ValueError(f"composed: the robot {self.robot.name!r} has no hand-merged scene; use composed=True")
        if composed:
            self.xml_file = None
            self.model = compose_scene(self.robot, ROBOT_PREFIX, TOOL_PREFIX)
            self._prefix = {"robot": ROBOT_PREFIX, "tool": TOOL_PREFIX}
        else:
            path = Path(self.robot.legacy_scene if xml_file is None else xml_file)
            if not path.is_file():
                raise ValueError(f"xml_file: no such file: {path}")
            self.xml_file = path
            self.model = mujoco.MjModel.from_xml_path(str(path))
            self._prefix = {"robot": "", "tool": ""}
        self.data = mujoco.MjData(self.model)
        self._check_names()
        self._read_joints()
        self._read_arena()
        self._read_sensors()
        self._read_robot_geoms()
        self.table_pose = TablePose()

    def name(self, part: str, name: str) -> str:
        """The model's name of ``name`` of ``part`` (``"robot"``, ``"tool"`` or ``"arena"``)."""
        return self._prefix.get(part, "") + name

    def id(self, obj: mujoco.mjtObj, part: str, name: str) -> int:
        """The model id of object ``name`` of ``part`` (-1 if there is none)."""
        return mujoco.mj_name2id(self.model, obj, self.name(part, name))

    def _check_names(self) -> None:
        """ValueError naming what the scene lacks."""
        robot, body, geom = self.robot, mujoco.mjtObj.mjOBJ_BODY, mujoco.mjtObj.mjOBJ_GEOM
        site = mujoco.mjtObj.mjOBJ_SITE
        sensors = ("wrist_force", "wrist_torque", "sponge_touch", "sponge_table", "robot_table",
                   *self_contact_sensors(robot), "arm_obstacle")
        required = [(body, "arena", ("table", "obstacle")), (geom, "arena", ("table_top", "obstacle")),
                    (body, "robot", (robot.root_body, robot.arm_root, *robot.body_links)),
                    (site, "robot", (robot.ft_site,)), (geom, "robot", robot.hand_geoms),
                    (mujoco.mjtObj.mjOBJ_JOINT, "robot", robot.joints), (body, "tool", ("sponge",)),
                    (geom, "tool", ("sponge",)), (site, "tool", ("sponge_tcp",)),
                    (mujoco.mjtObj.mjOBJ_JOINT, "tool", ("sponge_slide",)),
                    (mujoco.mjtObj.mjOBJ_JOINT, "arena", ("obstacle_free",)),
                    (mujoco.mjtObj.mjOBJ_SENSOR, "arena", sensors)]
        source = self.xml_file.name if self.xml_file is not None else "the composed scene"
        for obj, part, names in required:
            missing = [n for n in names if self.id(obj, part, n) < 0]
            if missing:
                raise ValueError(f"xml_file: {source} lacks the required {obj.name[6:].lower()}(s) {missing}")

    def _read_joints(self) -> None:
        m, joint = self.model, mujoco.mjtObj.mjOBJ_JOINT
        read_arm(self, m, tuple(self.name("robot", n) for n in self.robot.joints), "xml_file")
        self.slide_qpos = m.jnt_qposadr[self.id(joint, "tool", "sponge_slide")]

    def _read_arena(self) -> None:
        m, body, geom = self.model, mujoco.mjtObj.mjOBJ_BODY, mujoco.mjtObj.mjOBJ_GEOM
        self.table_body = self.id(body, "arena", "table")
        self.sponge_body = self.id(body, "tool", "sponge")
        self.sponge_geom = self.id(geom, "tool", "sponge")
        self.table_geom = self.id(geom, "arena", "table_top")
        self.sponge_half = m.geom_size[self.sponge_geom].copy()
        self.ft_site = self.id(mujoco.mjtObj.mjOBJ_SITE, "robot", self.robot.ft_site)
        self.sponge_site = self.id(mujoco.mjtObj.mjOBJ_SITE, "tool", "sponge_tcp")
        # The obstacle: a free body (cylinder) placed on the table or parked.
        self.obstacle_body = self.id(body, "arena", "obstacle")
        self.obstacle_geom = self.id(geom, "arena", "obstacle")
        free = self.id(mujoco.mjtObj.mjOBJ_JOINT, "arena", "obstacle_free")
        if (m.jnt_type[free] != mujoco.mjtJoint.mjJNT_FREE
                or m.geom_type[self.obstacle_geom] != mujoco.mjtGeom.mjGEOM_CYLINDER):
            raise ValueError("xml_file: 'obstacle_free' must be a free joint and geom 'obstacle' a cylinder")
        self.obstacle_qpos = int(m.jnt_qposadr[free])
        self.obstacle_dof = int(m.jnt_dofadr[free])
        self.obstacle_radius = float(m.geom_size[self.obstacle_geom, 0])
        self.obstacle_half_height = float(m.geom_size[self.obstacle_geom, 1])
        self._obstacle_collision = (int(m.geom_contype[self.obstacle_geom]),
                                    int(m.geom_conaffinity[self.obstacle_geom]))
        self.obstacle_xy: np.ndarray | None = None
        # The table top as a rectangle in the table frame: (x_low, x_high, y_low, y_high) (m).
        top = m.geom_pos[self.table_geom], m.geom_size[self.table_geom]
        self.table_extent = (float(top[0][0] - top[1][0]), float(top[0][0] + top[1][0]),
                             float(top[0][1] - top[1][1]), float(top[0][1] + top[1][1]))
        self.nominal_table_pos = m.body_pos[self.table_body].copy()
        self.nominal_table_rot = np.zeros(9)
        mujoco.mju_quat2Mat(self.nominal_table_rot, m.body_quat[self.table_body])
        self.nominal_table_rot = self.nominal_table_rot.reshape(3, 3)
        self.nominal_table_quat = m.body_quat[self.table_body].copy()

    def _read_sensors(self) -> None:
        m = self.model

        def adr(name: str) -> int:
            return int(m.sensor_adr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SENSOR, name)])

        self.force_adr = slice(adr("wrist_force"), adr("wrist_force") + 3)
        self.torque_adr = slice(adr("wrist_torque"), adr("wrist_torque") + 3)
        self.touch_adr = adr("sponge_touch")
        # MuJoCo contact sensors, evaluated in C at every step: sponge-table (found, net force [3],
        # world frame) and robot-subtree-table (found).
        self.sponge_contact_adr = adr("sponge_table")
        self.robot_contact_adr = adr("robot_table")
        # the arm touching each link of the robot's body (found, min distance), and the cup (found)
        self.self_contact_adr = tuple(adr(n) for n in self_contact_sensors(self.robot))
        self.obstacle_contact_adr = adr("arm_obstacle")
        if m.sensor_dim[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SENSOR, "sponge_table")] != 4:
            raise ValueError("xml_file: sensor 'sponge_table' must be a contact sensor with data=\"found force\" "
                             "and reduce=\"netforce\"")

    def _read_robot_geoms(self) -> None:
        """Robot = every body on the root body's subtree; arm-collision geoms = robot geoms but the sponge."""
        m = self.model
        root = self.id(mujoco.mjtObj.mjOBJ_BODY, "robot", self.robot.root_body)
        robot_bodies = {b for b in range(m.nbody) if self._descends(b, root)}
        robot_geom = np.array([int(m.geom_bodyid[g]) in robot_bodies for g in range(m.ngeom)])
        self.is_arm_geom = robot_geom.copy()
        self.is_arm_geom[self.sponge_geom] = False

    def _descends(self, body: int, root: int) -> bool:
        while body > 0:
            if body == root:
                return True
            body = int(self.model.body_parentid[body])
        return False

    @property
    def nominal_normal(self) -> np.ndarray:
        """Nominal table normal in the world frame, [3]."""
        return self.nominal_table_rot[:, 2].copy()

    def set_table(self, pose: TablePose) -> None:
        """Move the table body to the nominal pose shifted by ``pose`` (changes the model)."""
        rot = self.nominal_table_rot @ rotation_from_tilt(pose.tilt_x, pose.tilt_y)
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, rot.ravel())
        self.model.body_pos[self.table_body] = self.nominal_table_pos + np.array([0.0, 0.0, pose.height])
        self.model.body_quat[self.table_body] = quat
        self.table_pose = pose

    def place_obstacle(self, xy: np.ndarray | None) -> None:
        """Stand the obstacle upright on the actual table at table-frame ``xy`` [2] (m), or park it out of
        the scene (weightless, no collisions) with ``None``. Takes effect at the next :meth:`set_arm_state`."""
        m = self.model
        if xy is None:
            m.body_gravcomp[self.obstacle_body] = 1.0
            m.geom_contype[self.obstacle_geom] = 0
            m.geom_conaffinity[self.obstacle_geom] = 0
            self.obstacle_xy = None
            return
        m.body_gravcomp[self.obstacle_body] = 0.0
        m.geom_contype[self.obstacle_geom], m.geom_conaffinity[self.obstacle_geom] = self._obstacle_collision
        self.obstacle_xy = np.asarray(xy, dtype=np.float64).copy()

    def _obstacle_pose(self) -> np.ndarray:
        """qpos [7] of the obstacle: standing on the actual table at ``obstacle_xy``, or parked."""
        if self.obstacle_xy is None:
            return np.r_[OBSTACLE_PARKING, 1.0, 0.0, 0.0, 0.0]
        origin, rot = self.table_frame(actual=True)
        centre = origin + rot @ np.r_[self.obstacle_xy, self.obstacle_half_height + 1e-4]
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, rot.ravel())
        return np.r_[centre, quat]

    def obstacle_position(self) -> np.ndarray:
        """Current world position of the obstacle's centre, [3]."""
        return self.data.qpos[self.obstacle_qpos:self.obstacle_qpos + 3].copy()

    def control_frame(self) -> tuple[np.ndarray, np.ndarray]:
        """(origin [3], rotation [3, 3]) of the frame the controller plans in: the nominal table origin
        (the height offset is unknown to the controller and found by the force adaptation) with the
        actual table orientation (the tilt is in the context, so the sponge follows the actual normal)."""
        return self.nominal_table_pos.copy(), self.table_frame(actual=True)[1]

    @property
    def table_origin(self) -> np.ndarray:
        """The nominal table frame's origin in the world ``[3]`` (its axes are the world's before the tilt)."""
        return self.nominal_table_pos.copy()

    @property
    def sensor(self) -> dict[str, slice]:
        """Sensor name -> its columns of ``data.sensordata``."""
        m = self.model
        return {m.sensor(i).name: slice(int(m.sensor_adr[i]), int(m.sensor_adr[i] + m.sensor_dim[i]))
                for i in range(m.nsensor)}

    def table_frame(self, actual: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """(origin [3], rotation [3, 3]) of the actual (or nominal) table frame in the world."""
        if not actual:
            return self.nominal_table_pos.copy(), self.nominal_table_rot.copy()
        p = self.table_pose
        origin = self.nominal_table_pos + np.array([0.0, 0.0, p.height])
        return origin, self.nominal_table_rot @ rotation_from_tilt(p.tilt_x, p.tilt_y)

    def to_world(self, points: np.ndarray, actual: bool = False) -> np.ndarray:
        """Table-frame points [..., 3] to world points [..., 3] in the control frame (:meth:`control_frame`),
        or the actual table frame with ``actual``."""
        origin, rot = self.table_frame(True) if actual else self.control_frame()
        return np.asarray(points, dtype=np.float64) @ rot.T + origin

    def arm_qpos(self) -> np.ndarray:
        """Current positions of the ``n`` controlled joints, [n]."""
        return self.data.qpos[self.qpos_adr].copy()

    def set_arm_state(self, q: np.ndarray) -> None:
        """Reset the simulation to rest at joint positions ``q`` [n] with matching servo targets."""
        mujoco.mj_resetData(self.model, self.data)
        self.data.qpos[self.qpos_adr] = q
        self.data.qpos[self.obstacle_qpos:self.obstacle_qpos + 7] = self._obstacle_pose()
        self.data.ctrl[self.actuator_ids] = q
        mujoco.mj_forward(self.model, self.data)

    def wrist_force_world(self) -> np.ndarray:
        """Raw wrist force sensor reading rotated into the world frame, [3] (newtons)."""
        rot = self.data.site_xmat[self.ft_site].reshape(3, 3)
        return rot @ self.data.sensordata[self.force_adr]

    def servo_lead(self) -> np.ndarray:
        """``kv / kp`` of the arm's position servos, [n] (s): the lag a moving target sees."""
        return servo_lead(self.model, self.actuator_ids)
