"""The versions 1 and 2 of the wiping task as they were published: :class:`LegacyWipingTask`.

The current description (:class:`~rdmp_gym.envs.tasks.wiping.task.WipingTask`) with what the versions 1 and 2 do
differently (:data:`~rdmp_gym.envs.tasks.wiping.versions.TASK_VERSIONS`): the robot's hand-merged scene (or a given
``xml_file``), the pattern in place in version 1 (no covering sweep), the cup 1 cm from the patch and 35-60 % of the
way along the approach in version 1, plain jerk as the smoothness in version 1, no executable success in version 1,
no smooth-path success, the cup's displacement from where it was placed, and the simulated coverage of an episode
voided for a penetration.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from ....robots import RobotDescription
from ....smoothness import Smoothness
from ...description import Stage
from ..context import PATCH_CLEARANCE
from ..settings import EnvConfig
from ..task import DEFAULT_GROUPS, WipingTask
from ..versions import pad_clearance
from .scene import WipeScene

__all__ = ["LegacyWipingTask"]


class LegacyWipingTask(WipingTask):
    """The wiping task of the versions 1 and 2, on ARMAR-III's hand-merged scene; see the module docstring.

    Args:
        config, **settings: as :class:`~rdmp_gym.envs.tasks.wiping.task.WipingTask`'s (the version 1 or 2).
    """

    versions = (1, 2)
    max_jerk_ratio: ClassVar[float | None] = None
    cup_from_touch: ClassVar[bool] = False

    def _prepare_scene(self, config: EnvConfig) -> float:
        """The task's scene (:attr:`scene`: the robot's hand-merged scene, or the scene MJCF ``xml_file``) and its
        physics step (s): the scene's, or the one configured."""
        #: the scene the task runs on
        self.scene = WipeScene(self.robot, xml_file=config.xml_file)
        if config.timing.timestep is not None:
            self.scene.model.opt.timestep = config.timing.timestep
        return self.scene.model.opt.timestep

    def stage(self, robot: RobotDescription) -> Stage:
        """The task's scene (:attr:`scene`), timing, action map (with the approach and the sweep) and path IK (to the
        sponge's face centre)."""
        if robot.name != self.robot.name:
            raise ValueError(f"robot: the wiping task was built for {self.robot.name!r}, not {robot.name!r}")
        scene = self.scene
        self._staged(scene, scene.path_ik(), scene.parts, "", "")
        return Stage(scene, self.frame_skip, self.dt, self.n_steps, self.times, self.action_map, self.ik)

    def default_groups(self) -> tuple[str, ...]:
        """:data:`~rdmp_gym.envs.tasks.wiping.task.DEFAULT_GROUPS`, and from version 2 on the travelling anchor."""
        return (*DEFAULT_GROUPS, "sweep") if self.task_version.sweep else DEFAULT_GROUPS

    def _cup_placement(self) -> tuple[float, bool]:
        """Version 1: 1 cm from the patch, 35-60 % of the way along the approach; version 2: the current task's."""
        if self.task_version.pad_clearance:
            return pad_clearance(self.parts.sponge_half), True
        return PATCH_CLEARANCE, False

    def jerk_measure(self, path: np.ndarray, dt: float) -> float:
        """Version 1: integrated squared jerk; version 2: the current task's."""
        if self.task_version.speed_normalised_jerk:
            return Smoothness.speed_normalised(path, dt)
        return Smoothness.integrated_jerk(path, dt)

    @property
    def success_joint_accel(self) -> float | None:
        """Version 1: not checked (None); version 2: the robot's limit."""
        return self.reward_settings.max_joint_accel if self.task_version.executable_success else None

    def void_coverage(self, stats: dict[str, Any]) -> None:
        """An episode voided for a penetration keeps its simulated coverage."""
