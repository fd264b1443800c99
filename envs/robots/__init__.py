"""The robots of the wiping task: a registry of :class:`RobotDescription` by name.

Adding an arm is one folder with its description (and its MJCF, or a loader of a packaged one) and one line in
:data:`ROBOTS` (or a call of :func:`register_robot` from user code).
"""

from __future__ import annotations

from .armar3 import ARMAR3
from .description import BodyClearanceGeoms, RobotDescription, ToolMount
from .panda import PANDA

__all__ = ["ROBOTS", "BodyClearanceGeoms", "RobotDescription", "ToolMount", "get_robot", "register_robot"]

#: name -> description of every robot the task knows
ROBOTS: dict[str, RobotDescription] = {"armar3": ARMAR3, "panda": PANDA}


def register_robot(robot: RobotDescription) -> None:
    """Make ``robot`` available by its name (an existing name is replaced)."""
    if not isinstance(robot, RobotDescription):
        raise TypeError(f"robot: expected a RobotDescription, got {type(robot).__name__}")
    ROBOTS[robot.name] = robot


def get_robot(robot: str | RobotDescription) -> RobotDescription:
    """The description of ``robot`` (a registered name, or a description, returned as it is)."""
    if isinstance(robot, RobotDescription):
        return robot
    if robot not in ROBOTS:
        raise ValueError(f"robot: expected one of {sorted(ROBOTS)} or a RobotDescription, got {robot!r}")
    return ROBOTS[robot]
