"""The scene of a task on a robot: the room, the robot at its base pose and the task's tool, objects and sensors.

:func:`compose_task_scene` loads the room (``assets/room.xml``: floor, light, cameras, table; or the task's own,
:attr:`~rdmp_gym.envs.tasks.description.TaskDescription.room`), attaches the robot's MJCF with MuJoCo's ``MjSpec``,
adds the sensors every task reads of a robot (``robot_table``: a robot geom on the table; ``arm_<link>``: the moving
arm touching a link of the robot's own body) and lets the task add its own
(:meth:`~rdmp_gym.envs.tasks.description.TaskDescription.compose`). :class:`TaskScene` holds the compiled model and
data with the indices the controller and the simulation core need.
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np

from .action import ActionMap
from .arena import DIST, FOUND, MINDIST, add_contact_sensor, self_contact_sensors
from .ik import BodyClearance, PathIK
from .kinematics import ChainKinematics
from .robots import RobotDescription, get_robot
from .tasks.description import Stage, TaskDescription

__all__ = ["ROBOT_PREFIX", "ROOM_XML", "TOOL_PREFIX", "ArmScene", "TaskScene", "compose_task_scene", "read_arm",
           "rotation_from_tilt", "servo_lead"]

ROOM_XML = Path(__file__).resolve().parent / "assets" / "room.xml"
#: Prefixes of the robot's and the task tool's names in the scene (the room's, the objects' and the sensors' none).
ROBOT_PREFIX, TOOL_PREFIX = "robot/", "tool/"


def rotation_from_tilt(tilt_x: float, tilt_y: float) -> np.ndarray:
    """Rotation [3, 3] = R_y(tilt_y) @ R_x(tilt_x)."""
    cx, sx, cy, sy = np.cos(tilt_x), np.sin(tilt_x), np.cos(tilt_y), np.sin(tilt_y)
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cx, -sx], [0.0, sx, cx]])
    ry = np.array([[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]])
    return ry @ rx


def read_arm(scene: object, model: mujoco.MjModel, joints: tuple[str, ...], argument: str) -> None:
    """Set the arm's indices on ``scene`` for the model's ``joints`` (full names, chain order): ``joint_ids``,
    ``qpos_adr``, ``dof_adr``, ``joint_lower``, ``joint_upper`` and ``actuator_ids`` (each ``[n]``); ValueError
    naming ``argument`` where a joint has no joint actuator."""
    joint_ids = np.array([mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, n) for n in joints])
    actuator_of_joint = {int(model.actuator_trnid[a, 0]): a for a in range(model.nu)
                         if model.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_JOINT}
    missing = [n.split("/")[-1] for n, j in zip(joints, joint_ids, strict=True) if int(j) not in actuator_of_joint]
    if missing:
        raise ValueError(f"{argument}: no joint actuator for {missing}")
    scene.joint_ids = joint_ids
    scene.qpos_adr = model.jnt_qposadr[joint_ids].copy()
    scene.dof_adr = model.jnt_dofadr[joint_ids].copy()
    scene.joint_lower = model.jnt_range[joint_ids, 0].copy()
    scene.joint_upper = model.jnt_range[joint_ids, 1].copy()
    scene.actuator_ids = np.array([actuator_of_joint[int(j)] for j in joint_ids])


def servo_lead(model: mujoco.MjModel, actuator_ids: np.ndarray) -> np.ndarray:
    """``kv / kp`` of the position servos ``actuator_ids [n]``, ``[n]`` (s): the lag a moving target sees."""
    kp = model.actuator_gainprm[actuator_ids, 0]
    kv = -model.actuator_biasprm[actuator_ids, 2]
    return np.where(kp > 0, kv / np.where(kp > 0, kp, 1.0), 0.0)


def compose_task_scene(robot: RobotDescription, task: TaskDescription) -> mujoco.MjModel:
    """The compiled scene of ``task`` on ``robot`` (see the module docstring)."""
    spec = mujoco.MjSpec.from_file(str(ROOM_XML if task.room is None else task.room))
    frame = spec.worldbody.add_frame(pos=list(robot.base_pos), quat=list(robot.base_quat))
    spec.attach(robot.spec(), frame=frame, prefix=ROBOT_PREFIX)
    subtree, body = mujoco.mjtObj.mjOBJ_XBODY, mujoco.mjtObj.mjOBJ_BODY
    add_contact_sensor(spec, "robot_table", (subtree, ROBOT_PREFIX + robot.root_body),
                       (mujoco.mjtObj.mjOBJ_GEOM, "table_top"), FOUND)
    arm = (subtree, ROBOT_PREFIX + robot.arm_root)
    for name, link in zip(self_contact_sensors(robot), robot.body_links, strict=True):
        add_contact_sensor(spec, name, arm, (body, ROBOT_PREFIX + link), FOUND | DIST, MINDIST)
    task.compose(spec, robot, ROBOT_PREFIX, TOOL_PREFIX)
    return spec.compile()


class ArmScene:
    """What the faces use of a scene with an arm: rest at a posture and the servos' lead (a subclass sets ``model``,
    ``data`` and the arm's indices ``qpos_adr``, ``actuator_ids``, e.g. with :func:`read_arm`)."""

    model: mujoco.MjModel
    data: mujoco.MjData
    qpos_adr: np.ndarray
    actuator_ids: np.ndarray

    def set_arm_state(self, q: np.ndarray) -> None:
        """Reset the simulation to rest at joint positions ``q [n]`` with matching servo targets."""
        mujoco.mj_resetData(self.model, self.data)
        self.data.qpos[self.qpos_adr] = q
        self.data.ctrl[self.actuator_ids] = q
        mujoco.mj_forward(self.model, self.data)

    def servo_lead(self) -> np.ndarray:
        """``kv / kp`` of the arm's position servos ``[n]`` (s): the lag a moving target sees."""
        return servo_lead(self.model, self.actuator_ids)


class TaskScene(ArmScene):
    """The model and data of a task on a robot, with the arm's indices and the sensors' columns.

    Args:
        robot: a registered robot name or a :class:`~rdmp_gym.envs.robots.RobotDescription`.
        task: the task description.
    """

    def __init__(self, robot: str | RobotDescription, task: TaskDescription):
        self.robot = get_robot(robot)
        self.task = task
        self.model = compose_task_scene(self.robot, task)
        self.data = mujoco.MjData(self.model)
        read_arm(self, self.model, tuple(ROBOT_PREFIX + n for n in self.robot.joints), "robot")
        table = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, "table")
        #: the nominal table frame in the world: origin [3] (on the top surface), rotation [3, 3]
        self.table_origin = self.model.body_pos[table].copy()
        rotation = np.zeros(9)
        mujoco.mju_quat2Mat(rotation, self.model.body_quat[table])
        self.table_rotation = rotation.reshape(3, 3)
        #: sensor name -> its columns of ``data.sensordata``
        self.sensor = {self.model.sensor(i).name: slice(int(self.model.sensor_adr[i]),
                                                        int(self.model.sensor_adr[i] + self.model.sensor_dim[i]))
                       for i in range(self.model.nsensor)}
        self.tip_site = self.id(mujoco.mjtObj.mjOBJ_SITE, TOOL_PREFIX + task.tool_site)
        if self.tip_site < 0:
            raise ValueError(f"task: the tool of {type(task).__name__} has no site {task.tool_site!r} (tool_site)")

    def id(self, obj: mujoco.mjtObj, name: str) -> int:
        """The model id of object ``name`` (-1 if there is none)."""
        return mujoco.mj_name2id(self.model, obj, name)

    def path_ik(self) -> PathIK:
        """The path IK of the robot's chain to the task tool's site, with the robot's arm-from-body clearance."""
        robot, prefix = self.robot, ROBOT_PREFIX
        joints = tuple(prefix + n for n in robot.joints)
        geoms = robot.body_clearance
        bodies = () if geoms is None else tuple(prefix + n for n in (geoms.box_body, *geoms.capsule_bodies))
        kinematics = ChainKinematics(self.model, TOOL_PREFIX + self.task.tool_site, joints, bodies=bodies)
        clearance = None if geoms is None else BodyClearance(self.model, kinematics, prefix + geoms.box,
                                                             tuple(prefix + n for n in geoms.capsules))
        return PathIK(kinematics, robot.posture, robot.mobility, clearance=clearance)

    def table_to_world(self, points: np.ndarray) -> np.ndarray:
        """Nominal table-frame points ``[..., 3]`` in the world frame."""
        return np.asarray(points, dtype=np.float64) @ self.table_rotation.T + self.table_origin


def standard_stage(task: TaskDescription, robot: RobotDescription, action_map: ActionMap | None = None) -> Stage:
    """The stage a face runs ``task`` on with ``robot`` where the task gives none: the room composed with the robot
    and the task (:class:`TaskScene`); the task's :attr:`control_rate` and :attr:`duration` in its physics steps; the
    action map of the task's groups and scales (or ``action_map``, the task's own); the scene's path inverse
    kinematics."""
    scene = TaskScene(robot, task)
    timestep = scene.model.opt.timestep
    frame_skip = max(1, round(1.0 / (task.control_rate * timestep)))
    dt = frame_skip * timestep
    n_steps = max(2, round(task.duration / dt))
    if action_map is None:
        action_map = ActionMap(task.imitation(), task.groups, task.scales)
    return Stage(scene, frame_skip, dt, n_steps, np.arange(n_steps) * dt, action_map, scene.path_ik())
