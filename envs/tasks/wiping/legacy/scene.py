"""The hand-merged wiping scene that the versions 1 and 2 run on: :class:`WipeScene`."""

from __future__ import annotations

from pathlib import Path

import mujoco

from ....ik import BodyClearance, PathIK
from ....kinematics import ChainKinematics
from ....robots import ARMAR3, RobotDescription, get_robot
from ....task_scene import ArmScene, read_arm
from ..scene import WipeParts

__all__ = ["DEFAULT_XML", "WipeScene"]

#: The packaged ARMAR-III scene of ``ArmarWipe-v1`` and ``-v2``.
DEFAULT_XML = Path(ARMAR3.legacy_scene)


class WipeScene(ArmScene):
    """The MuJoCo model and data of a hand-merged wiping scene, with the arm's indices and the task's parts.

    Args:
        robot: the robot (a registered name or a :class:`~rdmp_gym.envs.robots.RobotDescription`) with a
            ``legacy_scene``, the scene loaded without ``xml_file``.
        xml_file: a hand-merged scene MJCF instead (with the names of the robot's description, the arena's and the
            sponge tool's, and the sensors of the wiping task, unprefixed).
    """

    def __init__(self, robot: str | RobotDescription = "armar3", xml_file: str | Path | None = None):
        self.robot = get_robot(robot)
        if xml_file is None and self.robot.legacy_scene is None:
            raise ValueError(f"xml_file: the robot {self.robot.name!r} has no hand-merged scene; give xml_file")
        path = Path(self.robot.legacy_scene if xml_file is None else xml_file)
        if not path.is_file():
            raise ValueError(f"xml_file: no such file: {path}")
        self.xml_file = path
        self.model = mujoco.MjModel.from_xml_path(str(path))
        self.data = mujoco.MjData(self.model)
        #: where the task's objects and sensors are (read before anything moves them)
        self.parts = WipeParts.read(self.model, self.robot, source=path.name)
        read_arm(self, self.model, self.robot.joints, "xml_file")
        #: the nominal table frame's origin in the world ``[3]``
        self.table_origin = self.parts.table_origin.copy()
        #: sensor name -> its columns of ``data.sensordata``
        self.sensor = {self.model.sensor(i).name: slice(int(self.model.sensor_adr[i]),
                                                        int(self.model.sensor_adr[i] + self.model.sensor_dim[i]))
                       for i in range(self.model.nsensor)}

    def path_ik(self) -> PathIK:
        """The path IK of the robot's chain to the sponge's face centre, with its arm-from-body clearance."""
        robot, model = self.robot, self.model
        geoms = robot.body_clearance
        bodies = () if geoms is None else (geoms.box_body, *geoms.capsule_bodies)
        kinematics = ChainKinematics(model, "sponge_tcp", robot.joints, bodies=bodies)
        clearance = None if geoms is None else BodyClearance(model, kinematics, geoms.box, geoms.capsules)
        return PathIK(kinematics, robot.posture, robot.mobility, clearance=clearance)
