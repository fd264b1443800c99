"""The simulation core of the rhythmic tasks: servo targets, physics and a record at every physics step.

One control step sets the arm's position-servo targets and runs ``frame_skip`` physics steps, copying MuJoCo's
whole ``sensordata`` after each (at 500 Hz with the room's 2 ms step: a strike's contact force, a brief touch),
and the state after the control step. The task reads what it needs from the record afterwards, by sensor name.
The episodic face runs it along a whole joint-target plan; the step twin one control step per ``step``.
A simulation that diverges (NaN, or MuJoCo resetting the data on bad accelerations) ends the episode there.
"""

from __future__ import annotations

from collections.abc import Callable

import mujoco
import numpy as np

from .task_scene import TaskScene

__all__ = ["ServoSimulation"]


class ServoSimulation:
    """Control steps of a task scene, recorded; see the module docstring.

    Args:
        scene: the scene, reset to rest at the first joint targets with the task's objects in place.
        count: control steps of the episode (``T``).
        frame_skip: physics steps per control step.
    """

    def __init__(self, scene: TaskScene, count: int, frame_skip: int):
        if frame_skip < 1:
            raise ValueError(f"frame_skip: expected an integer >= 1, got {frame_skip!r}")
        m = scene.model
        self.scene, self.count, self.frame_skip = scene, count, frame_skip
        #: sensordata after every physics step ``[T * frame_skip, S]``
        self.sensors = np.zeros((count * frame_skip, m.nsensordata))
        #: state and tool-tip position after every control step
        self.qpos = np.zeros((count, m.nq))
        self.qvel = np.zeros((count, m.nv))
        self.tip = np.zeros((count, 3))
        self.steps = count
        self.unstable = False
        self._last_time = scene.data.time

    def step(self, k: int, target: np.ndarray) -> bool:
        """Control step ``k`` with servo targets ``target [n]`` (clipped to the joint limits). Returns True when the
        simulation diverged (the episode ends with step ``k``)."""
        scene = self.scene
        m, d = scene.model, scene.data
        d.ctrl[scene.actuator_ids] = np.clip(target, scene.joint_lower, scene.joint_upper)
        row = k * self.frame_skip
        for i in range(self.frame_skip):
            mujoco.mj_step(m, d)
            self.sensors[row + i] = d.sensordata
        self.qpos[k], self.qvel[k] = d.qpos, d.qvel
        self.tip[k] = d.site_xpos[scene.tip_site]
        diverged = d.time <= self._last_time or not np.isfinite(d.qpos).all()
        self._last_time = d.time
        if diverged:
            self.steps, self.unstable = k + 1, True
        return diverged

    def run(self, targets: np.ndarray, callback: Callable[[int], None] | None = None) -> None:
        """Run the episode's control steps with the joint targets ``targets [T, n]`` (stops where it diverges);
        ``callback(k)`` after control step ``k`` (e.g. to grab video frames)."""
        for k in range(self.count):
            if self.step(k, targets[k]):
                break
            if callback is not None:
                callback(k)
