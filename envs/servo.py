"""The simulation core of the rhythmic tasks: servo targets, physics and a record of every control step.

One control step of :class:`ServoSimulation`:

1. the servo targets: the plan's joint targets, clipped to the joint limits, or what the task's hook makes of them
   (:meth:`StepHook.command`; e.g. the wiping task adapts its pressing depth online from the wrist force);
2. the physics: ``frame_skip`` physics steps, one at a time where the step asks for them (:meth:`StepHook.substeps`,
   with :meth:`StepHook.substep` after each: every sensor at every physics step, or the peak of a touchdown's force)
   or all at once;
3. the record (:meth:`StepHook.finish`), which also says whether the simulation diverged.

Without a hook the core is its own: it records MuJoCo's whole ``sensordata`` after every physics step (at 500 Hz
with the room's 2 ms step: a strike's contact force, a brief touch) and the state after the control step; the task
reads what it needs from the record afterwards, by sensor name. The episodic face runs the core along a whole
joint-target plan, the step twin one control step per ``step``. A simulation that diverges (NaN, or MuJoCo resetting
the data on bad accelerations) ends the episode there.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol

import mujoco
import numpy as np

__all__ = ["ServoSimulation", "StepHook"]


class StepHook(Protocol):
    """What a task adds to a control step of the core (see the module docstring); ``k`` is the control step."""

    def command(self, k: int, target: np.ndarray) -> None:
        """Write the servo targets of step ``k`` for the plan's joint targets ``target [n]`` into the data."""

    def substeps(self, k: int) -> bool:
        """Whether step ``k`` runs its physics steps one at a time (calling :meth:`substep` after each)."""

    def substep(self, k: int, i: int) -> None:
        """After physics step ``i`` of control step ``k`` (only where :meth:`substeps`)."""

    def finish(self, k: int) -> bool:
        """Record control step ``k`` after its physics; True when the simulation diverged (the episode ends)."""


class ServoSimulation:
    """Control steps of a scene, recorded; see the module docstring.

    Args:
        scene: the scene, reset to rest at the first joint targets with the task's objects in place (its ``model``,
            ``data``, the arm's ``actuator_ids``, ``joint_lower``, ``joint_upper`` and the tool's ``tip_site``).
        count: control steps of the episode (``T``).
        frame_skip: physics steps per control step.
        hook: the task's :class:`StepHook` (default: none, the core's own record of every sensor at every physics
            step).
    """

    def __init__(self, scene: Any, count: int, frame_skip: int, hook: StepHook | None = None):
        if frame_skip < 1:
            raise ValueError(f"frame_skip: expected an integer >= 1, got {frame_skip!r}")
        m = scene.model
        self.scene, self.count, self.frame_skip = scene, count, frame_skip
        #: the task's hook (the core itself without one)
        self.hook: StepHook = self if hook is None else hook
        if hook is None:
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
        """Control step ``k`` with the plan's servo targets ``target [n]``. Returns True when the simulation diverged
        (the episode ends with step ``k``)."""
        m, d, hook = self.scene.model, self.scene.data, self.hook
        hook.command(k, target)
        if hook.substeps(k):
            substep = hook.substep
            for i in range(self.frame_skip):
                mujoco.mj_step(m, d)
                substep(k, i)
        else:
            mujoco.mj_step(m, d, self.frame_skip)
        diverged = hook.finish(k)
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

    # ------------------------------------------------------------------ the core's own hook
    def command(self, k: int, target: np.ndarray) -> None:
        """The plan's targets, clipped to the joint limits."""
        scene = self.scene
        scene.data.ctrl[scene.actuator_ids] = np.clip(target, scene.joint_lower, scene.joint_upper)

    def substeps(self, k: int) -> bool:
        """Every physics step is recorded."""
        return True

    def substep(self, k: int, i: int) -> None:
        """Copy the sensors after physics step ``i`` of control step ``k``."""
        self.sensors[k * self.frame_skip + i] = self.scene.data.sensordata

    def finish(self, k: int) -> bool:
        """Record the state and the tool tip; diverged where time did not advance or the state is not finite."""
        d = self.scene.data
        self.qpos[k], self.qvel[k] = d.qpos, d.qvel
        self.tip[k] = d.site_xpos[self.scene.tip_site]
        diverged = d.time <= self._last_time or not np.isfinite(d.qpos).all()
        self._last_time = d.time
        return diverged
