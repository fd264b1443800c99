"""The table-wiping task as one :class:`~rdmp_gym.envs.tasks.description.TaskDescription`.

:class:`WipingTask` is everything the envs know of wiping: the objects it adds to the arena (the sponge tool on the
robot's mount and the sensors it reads, :meth:`WipingTask.compose`; the table and the cup stand in the wiping arena,
:attr:`WipingTask.room`), the context (drawn, validated and observed: :mod:`~rdmp_gym.envs.tasks.wiping.context`; the
table pose and the cup placed for it, :meth:`WipingTask.place`), the imitation DMP and the action layout (its
parameter groups, the lifted approach and the covering sweep), the plan (the DMP anchored at the patch, started at
the sponge), the controller's force adaptation and the dirt (the wiping hook on the simulation core,
:mod:`~rdmp_gym.envs.tasks.wiping.simulation`), the judgement (the reward terms of
:mod:`~rdmp_gym.envs.tasks.wiping.reward`, the statistics and info keys of :mod:`~rdmp_gym.envs.tasks.wiping.info`,
``is_success`` and its failure causes) and the defaults a learner reads (:data:`LEARNER_DEFAULTS
<rdmp_gym.envs.tasks.wiping.versions.LEARNER_DEFAULTS>`).

The wiping ids' episodic envs are the generic face (:class:`~rdmp_gym.envs.rhythmic_env.RhythmicTaskEnv`), which runs
this description's hooks on the standard stage (the arena composed with the robot and the task, the task's timing
and action map, the path IK to the sponge's face centre), and which owns the episode: its context (passed to every
hook that needs it) and what the frames draw (the dirt as worn, :meth:`WipingTask.render_overlay`). Beside the
defaults the description sets the rest pose at the sponge start, the amplitude check (``"r0"``), the path checks (the
sponge flat within the engage height, the cup clearance), the wiping hook on the simulation core and the invalid
penalty. The step ids are the generic step twin (:class:`~rdmp_gym.envs.rhythmic_step.RhythmicTaskStepEnv`) with the
task's step book (:meth:`WipingTask.step_book`, :class:`~rdmp_gym.envs.tasks.wiping.step.WipeStepBook`). The
versions 1 and 2 are frozen apart (:mod:`~rdmp_gym.envs.tasks.wiping.legacy`); :meth:`WipingTask.build` gives the
description of a version.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from functools import lru_cache, partial
from pathlib import Path
from typing import Any, ClassVar

import mujoco
import numpy as np

from rdmp_gym import RhythmicDMP, load_dmp, wiping_demonstration
from rdmp_gym.dmp.fitting import FADE_BEFORE_T
from rdmp_gym.dmp.pose import PoseDMP
from rdmp_gym.signals.demonstrations import check_frame

from ...action import ActionMap
from ...contract import Metric
from ...controller import ForceAdaptation, ForceAdaptationSettings
from ...ik import IKResult, PathIK
from ...recording import SceneRenderer
from ...robots import RobotDescription, get_robot
from ...task_scene import ROBOT_PREFIX, TOOL_PREFIX, standard_stage
from ..description import Outcome, Rejection, Solution, Stage, TaskDescription, TaskPlan, ToolPath
from .approach import approach_direction, lift_profile
from .arena import ARENA_XML, add_task
from .clearance import Cup, CupClearance, HandPoints
from .context import CONTEXT_FIELDS, Context, ContextSpec
from .coverage import COVERING_FIGURE, covering_sweep, sweep_directions
from .force_learning import ForceProfileLearning, ForceProfileSettings
from .info import void_statistics
from .reward import RewardSettings, RewardWeights, Smoothness, invalid_reward, wipe_reward
from .scene import TablePose, WipeParts, control_frame, dirt_grid, place_objects, table_frame, to_world
from .settings import DEFAULT_TIMESTEP, EnvConfig, ForceConfig, RewardConfig, TaskConfig
from .simulation import DirtField, SimulationSettings, WipeTrace, simulate_wipe
from .step import WipeStepBook
from .versions import LEARNER_DEFAULTS, MAX_JERK_RATIO, TASK_VERSIONS, TaskVersion, pad_clearance

__all__ = ["DEFAULT_GROUPS", "WipeRecord", "WipingTask", "episode_success", "failure_causes", "outcome"]

logger = logging.getLogger(__name__)

#: ``info["is_success"]`` thresholds: coverage, force-in-band fraction, obstacle displacement (m).
SUCCESS_COVERAGE = 0.95
SUCCESS_FORCE_IN_BAND = 0.9
SUCCESS_OBSTACLE_SHIFT = 0.005
#: The action groups when ``groups`` is not given (``ArmarWipe-v2`` adds ``"sweep"``).
DEFAULT_GROUPS = ("periodic", "transient", "initial", "amplitude", "approach")
#: The sweep's last via point (the patch centre) comes this long (s) before the end of the episode.
SWEEP_END_MARGIN = 0.5


def failure_causes(stats: Mapping[str, Any], max_joint_accel: float | None = None,
                   max_jerk_ratio: float | None = None) -> tuple[str, ...]:
    """The ``is_success`` criteria that an episode's statistics (``ArmarWipeEnv``'s info) miss, in the order
    ``"coverage"``, ``"force"``, ``"arm collision"``, ``"self-collision"``, ``"cup"`` (touched or moved), with
    ``max_joint_accel`` (rad/s², executable success) ``"joint acceleration"`` (the peak above it) and
    ``"joint limit"``, and with ``max_jerk_ratio`` ``"jerk"`` (the path's jerk ratio above it); empty for a success
    (validity is checked apart)."""
    met = {"coverage": stats["coverage"] >= SUCCESS_COVERAGE,
           "force": stats["force_in_band_fraction"] >= SUCCESS_FORCE_IN_BAND,
           "arm collision": stats["arm_collision_fraction"] == 0.0,
           "self-collision": stats["self_collision_fraction"] == 0.0,
           "cup": stats["obstacle_touch_steps"] == 0 and stats["obstacle_shift"] < SUCCESS_OBSTACLE_SHIFT}
    if max_joint_accel is not None:
        met["joint acceleration"] = stats["peak_joint_accel"] <= max_joint_accel
        met["joint limit"] = stats["joint_limit_fraction"] == 0.0
    if max_jerk_ratio is not None:
        met["jerk"] = stats["jerk_ratio"] <= max_jerk_ratio
    return tuple(name for name, ok in met.items() if not ok)


def episode_success(stats: Mapping[str, Any], max_joint_accel: float | None = None,
                    max_jerk_ratio: float | None = None) -> bool:
    """Whether an episode's statistics meet the ``is_success`` thresholds: no :func:`failure_causes`."""
    return not failure_causes(stats, max_joint_accel, max_jerk_ratio)


def outcome(stats: Mapping[str, Any], valid: bool, unstable: bool, max_joint_accel: float | None,
            max_jerk_ratio: float | None = None) -> tuple[bool, tuple[str, ...]]:
    """``(is_success, causes)`` of an episode: ``("invalid",)`` or ``("unstable",)`` first, else
    :func:`failure_causes`."""
    if not valid or unstable:
        causes: tuple[str, ...] = ("invalid",) if not valid else ("unstable",)
    else:
        causes = failure_causes(stats, max_joint_accel, max_jerk_ratio)
    return not causes, causes


@lru_cache(maxsize=16)
def _fit_style(style: int, n_periodic: int, n_transient: int, method: str) -> RhythmicDMP:
    """Imitation DMP of a synthetic wiping demonstration (cached: fitting takes ~0.5 s), fitted with the settings
    the tasks were published with (:data:`rdmp_gym.dmp.fitting.FADE_BEFORE_T`), whatever the library's defaults."""
    return RhythmicDMP.fit(wiping_demonstration(style=style, rng=0), n_periodic=n_periodic,
                           n_transient=n_transient, method=method, **FADE_BEFORE_T)


def _with_covering_sweep(dmp: RhythmicDMP, transient: float, end: float) -> RhythmicDMP:
    """``dmp`` with the covering sweep from the end of the transient to :data:`SWEEP_END_MARGIN` s before
    ``end`` (a DMP that has a sweep keeps it: e.g. a refined ``dmp.json``, whose via points are its imitation)."""
    if dmp.sweep is not None:
        if dmp.sweep.n_points != len(COVERING_FIGURE):
            raise ValueError(f"dmp: its sweep has {dmp.sweep.n_points} via points; the env's sweep action needs the "
                             f"covering sweep's {len(COVERING_FIGURE)} (rdmp_gym.envs.tasks.wiping.coverage)")
        return dmp
    if end - SWEEP_END_MARGIN <= transient:
        raise ValueError(f"duration: {end:.3g} s leaves no time for the sweep after the transient ({transient:.3g} s)")
    return dmp.with_sweep(covering_sweep(transient, end - SWEEP_END_MARGIN, dmp.n_dims))


def _workspace_excess(path: np.ndarray, workspace: tuple[np.ndarray, np.ndarray]) -> float:
    """How far (m) ``path [T, 3]`` leaves the ``workspace`` box ``(low [3], high [3])`` at most (0 inside)."""
    low, high = workspace
    return float(np.max(np.maximum(low - path, 0.0) + np.maximum(path - high, 0.0)))


def _check_reach(spec: ContextSpec, robot: RobotDescription) -> None:
    """ValueError naming ``context_ranges`` unless every drawable patch (with the pad around its edge) and sponge
    start lies inside the robot's workspace (the nominal table frame)."""
    low, high = robot.workspace
    centre, size = CONTEXT_FIELDS["patch_centre"], CONTEXT_FIELDS["patch_size"]
    start = CONTEXT_FIELDS["sponge_start"]
    reach = spec.high[size[0]:size[0] + 2] / 2 + 0.05                       # half the patch + the pad's reach
    patch_low = spec.low[centre[0]:centre[0] + 2] - reach
    patch_high = spec.high[centre[0]:centre[0] + 2] + reach
    starts = slice(start[0], start[0] + 3)
    if (np.any(patch_low < low[:2]) or np.any(patch_high > high[:2]) or np.any(spec.low[starts] < low)
            or np.any(spec.high[starts] > high)):
        raise ValueError(f"context_ranges: the drawn patches {patch_low}..{patch_high} or sponge starts "
                         f"{spec.low[starts]}..{spec.high[starts]} leave the robot {robot.name!r}'s workspace "
                         f"{low}..{high} (table frame, m)")


def _saved_dmp(dmp: str | RhythmicDMP, workspace: tuple[np.ndarray, np.ndarray]) -> RhythmicDMP:
    """A 3-D DMP from a ``dmp.json`` path (or as given; of a pose DMP its position), its imitation path checked
    against ``workspace``."""
    if not isinstance(dmp, RhythmicDMP):
        if not Path(dmp).is_file():
            raise FileNotFoundError(f"dmp: no such file {dmp}")
        dmp = load_dmp(dmp)
        dmp = dmp.position if isinstance(dmp, PoseDMP) else dmp
    if dmp.n_dims != 3:
        raise ValueError(f"dmp: expected 3 dimensions (x, y, z in the table frame), got {dmp.n_dims}")
    t = np.arange(0.0, dmp.transients[0].length + 2.0 * dmp.period, 0.01)
    check_frame(dmp.rollout(t), *workspace, centre_dims=(0, 1), name="dmp")
    return dmp


@dataclass(frozen=True)
class WipeRecord:
    """What the wiping task judges of an executed episode beside the tool path
    (:attr:`ToolPath.record <rdmp_gym.envs.tasks.description.ToolPath>`).

    Attributes:
        trace: the episode's :class:`~rdmp_gym.envs.tasks.wiping.simulation.WipeTrace` (the simulation hook's).
        smooth: the commanded motion's :class:`~rdmp_gym.envs.smoothness.Smoothness` (the version's jerk measure).
        penetration_limit: the penetration (m) of a robot geom into the robot's body or the table beyond which the
            episode is void.
    """

    trace: WipeTrace
    smooth: Smoothness
    penetration_limit: float

    def dirt_left(self) -> np.ndarray:
        """Dirt left per cell ``[N]`` at the end of the episode (what its frames draw)."""
        return self.trace.dirt


class WipingTask(TaskDescription):
    """Table wiping with a sponge; see the module docstring.

    Args:
        config: all settings at once (:class:`~rdmp_gym.envs.tasks.wiping.settings.EnvConfig`; default
            ``EnvConfig()``, the current version).
        **settings: keywords of the settings (the wiping env's; they change ``config``).
    """

    name = "Wipe"
    versions = (3,)
    tool_site = "sponge_tcp"
    #: the wiping arena: the standard room and the cup
    room = ARENA_XML
    #: the approach and the sweep are action dimensions of the DMP's action map (fixed directions in theta)
    extras: Mapping[str, float] = {}
    #: the frames are square by default
    frame_size: ClassVar[tuple[int, int]] = (480, 480)
    #: settings a learner reads, per version (:data:`rdmp_gym.envs.tasks.wiping.versions.LEARNER_DEFAULTS`)
    defaults_by_version: ClassVar[Mapping[int, Mapping[str, Mapping[str, Any]]]] = LEARNER_DEFAULTS
    #: ``is_success`` needs the path's jerk within this factor of the imitation's (None: not checked)
    max_jerk_ratio: ClassVar[float | None] = MAX_JERK_RATIO
    #: the cup's displacement counts from the robot's first touch (else from where it was placed)
    cup_from_touch: ClassVar[bool] = True
    #: per episode: the share of the dirt wiped, and the share of the wiping time with the contact force in band
    metrics = (Metric("coverage", "coverage"), Metric("force_in_band_fraction", "force in band"))

    def __init__(self, config: EnvConfig | None = None, **settings: Any):
        config = EnvConfig.from_kwargs(**settings) if config is None else config.replace(**settings)
        if config.task.version not in self.versions:
            raise ValueError(f"version: {type(self).__name__} describes the version(s) {list(self.versions)}, got "
                             f"{config.task.version!r} (WipingTask.build and the task's name \"wipe\" build every "
                             f"version's description)")
        #: every setting of the task (saves to and loads from JSON)
        self.config = config
        #: what this task version changes (see :mod:`rdmp_gym.envs.tasks.wiping.versions`)
        self.task_version: TaskVersion = TASK_VERSIONS[config.task.version]
        self.version = config.task.version
        #: the robot (:mod:`rdmp_gym.envs.robots`)
        self.robot: RobotDescription = get_robot(config.robot)
        self.dmp = self._imitation(config.task)
        self._set_groups(config.task)
        #: the physics step (s)
        self.timestep = self._prepare_scene(config)
        self._set_timing(config)
        #: the episode's length (s)
        self.duration = self.n_steps * self.dt
        self._set_action(config.task)
        self.scales = dict(config.task.scales or {})
        self._set_force_and_reward(config.force, config.reward)
        self._set_limits(config.task)
        self.obstacle = config.context.obstacle
        #: the clearance term that keeps the hand away from the cup (None: off)
        clearance = config.task.cup_clearance            # validated by TaskConfig: a margin (m), a term or None
        self.cup_clearance = CupClearance(margin=clearance) if isinstance(clearance, float) else clearance
        self._engage = self.adaptation_settings.engage_height
        self._imitation_paths: tuple[np.ndarray, np.ndarray] | None = None
        #: record the sponge-table force at every physics step into ``info["fine_force_trace"]``
        self.fine_force = False

    @classmethod
    def build(cls, config: EnvConfig | None = None, **settings: Any) -> WipingTask:
        """The description of the settings' version: a :class:`WipingTask`, or for the versions 1 and 2 their frozen
        description (:class:`~rdmp_gym.envs.tasks.wiping.legacy.task.LegacyWipingTask`)."""
        from .legacy.task import LegacyWipingTask

        config = EnvConfig.from_kwargs(**settings) if config is None else config.replace(**settings)
        return (LegacyWipingTask if config.task.version in LegacyWipingTask.versions else cls)(config)

    @classmethod
    def defaults_for(cls, version: int) -> Mapping[str, Mapping[str, Any]]:
        """The learner defaults of ``version``."""
        return cls.defaults_by_version.get(version, {})

    @classmethod
    def face_settings(cls, robot: str | RobotDescription, version: int) -> dict[str, Any]:
        """The robot and the version are the task's settings (its scene, plan and judgement depend on them)."""
        return {"robot": robot, "version": version}

    @classmethod
    def typed_settings(cls, settings: Mapping[str, Any]) -> EnvConfig:
        """The settings as one :class:`~rdmp_gym.envs.tasks.wiping.settings.EnvConfig` (each checked by name)."""
        return EnvConfig.from_kwargs(**settings)

    @property
    def learner_defaults(self) -> Mapping[str, Mapping[str, Any]]:  # type: ignore[override]
        """The learner defaults of this version."""
        return self.defaults_for(self.version)

    @property
    def smoothness_measure(self) -> str:  # type: ignore[override]
        """The version's jerk measure (v2 on: per unit of squared speed, :meth:`Smoothness.speed_normalised`)."""
        return "speed_normalised_jerk" if self.task_version.speed_normalised_jerk else "jerk"

    def context_fields(self) -> Mapping[str, tuple[int, int]]:
        """The observation's fields (:data:`~rdmp_gym.envs.tasks.wiping.context.CONTEXT_FIELDS`)."""
        return CONTEXT_FIELDS

    # ------------------------------------------------------------------ construction stages
    def _imitation(self, task: TaskConfig) -> RhythmicDMP:
        """The imitation DMP: a saved one, one fitted to the given demonstration, or the built-in style's."""
        if task.dmp is not None:
            return _saved_dmp(task.dmp, self.robot.workspace)
        if task.demonstration is not None:
            task.demonstration.check_frame(*self.robot.workspace, centre_dims=(0, 1), name="demonstration")
            return RhythmicDMP.fit(task.demonstration, n_periodic=task.n_periodic, n_transient=task.n_transient,
                                   method=task.fit_method, **FADE_BEFORE_T)
        return _fit_style(task.style, task.n_periodic, task.n_transient, task.fit_method)

    def _prepare_scene(self, config: EnvConfig) -> float:
        """What the task's scene needs before the timing, and its physics step (s): the scene is composed from the
        arena, the robot and the sponge tool on the arena's step or the one configured (:meth:`compose` sets it)."""
        if config.xml_file is not None:
            raise ValueError(f"xml_file: a hand-merged scene serves the versions 1 and 2; version {self.version} "
                             f"composes its scene from the arena, the robot and the sponge tool (got "
                             f"{config.xml_file!r})")
        return DEFAULT_TIMESTEP if config.timing.timestep is None else config.timing.timestep

    def default_groups(self) -> tuple[str, ...]:
        """The action's parameter groups where none are given: :data:`DEFAULT_GROUPS` and the travelling anchor."""
        return (*DEFAULT_GROUPS, "sweep")

    def _cup_placement(self) -> tuple[float, bool]:
        """``(clearance, near_patch)`` of the cup (:class:`~rdmp_gym.envs.tasks.wiping.context.ContextSpec`): the
        pad's clearance (:func:`~rdmp_gym.envs.tasks.wiping.versions.pad_clearance`), anywhere near the patch."""
        return pad_clearance(self.parts.sponge_half), True

    def _set_groups(self, task: TaskConfig) -> None:
        groups = self.default_groups() if task.groups is None else task.groups
        #: the DMP parameter groups of theta (the ``approach`` and ``sweep_x``/``sweep_y`` dimensions come after
        #: them in the action; the ``sweep`` via points have none of their own)
        self.groups = tuple(group for group in groups if group != "approach")
        self._approach = "approach" in groups
        # The demonstrated pattern is centred on its anchor; the env re-anchors it at the patch centre,
        # keeping the demonstration's height offset of the anchor (0 for a pattern on the surface).
        self._anchor_z = float(self.dmp.anchor[2])

    def _set_timing(self, config: EnvConfig) -> None:
        """The control rate and the episode's control steps on the physics step :attr:`timestep`."""
        timing, task = config.timing, config.task
        self.frame_skip = timing.frame_skip_for(self.timestep)
        self.dt = self.frame_skip * self.timestep
        self.control_rate = 1.0 / self.dt
        transient = self.dmp.transients[0].length
        duration = task.duration
        if duration is None:
            n_periods = self.task_version.n_periods if task.n_periods is None else task.n_periods
            duration = transient + n_periods * self.dmp.period
        self.n_steps = max(2, round(duration / self.dt))
        self.times = np.arange(self.n_steps) * self.dt
        self.periodic = self.times >= transient
        if not self.periodic.any():
            raise ValueError(f"duration: {duration} s ends before the transient ({transient:.3g} s)")

    def _set_action(self, task: TaskConfig) -> None:
        """The action map: the parameter groups, the approach and the covering sweep."""
        transient = self.dmp.transients[0].length
        directions = {}
        if "sweep" in self.groups:
            self.dmp = _with_covering_sweep(self.dmp, transient, self.times[-1])
        if self._approach:
            directions["approach"] = approach_direction(self.dmp, self.groups, self.times, height=1.0)
        if "sweep" in self.groups:
            directions.update(sweep_directions(self.dmp, self.groups))
        self.action_map = ActionMap(self.dmp, self.groups, task.scales, directions, driven=("sweep",) if
                                    "sweep" in self.groups else ())

    def _set_force_and_reward(self, force: ForceConfig, reward: RewardConfig) -> None:
        self.force_band = force.force_band
        self.adaptation_settings = ForceAdaptationSettings(target_force=force.target_force, enabled=force.adaptation,
                                                           gain=force.admittance_gain)
        self.force_learning = (ForceProfileSettings() if force.force_learning is True
                               else force.force_learning or None)
        self.reward_settings = RewardSettings(target_force=force.target_force,
                                              max_joint_accel=self.robot.max_joint_accel,
                                              force_sigma=force.force_sigma, max_force=force.force_band[1],
                                              event_charge=self.task_version.event_charge,
                                              coverage_timing=reward.coverage_timing)
        self.reward_weights = RewardWeights.from_mapping(reward.weights)

    def _set_limits(self, task: TaskConfig) -> None:
        self.cell_size = task.cell_size
        self.limit_margin = task.limit_margin
        self.ik_tolerance = task.ik_tolerance
        self.max_joint_speed = self.robot.max_joint_speed if task.max_joint_speed is None else task.max_joint_speed
        self.wear_rate = task.wear_rate
        self.penetration_limit = task.penetration_limit

    def hand_points(self) -> HandPoints:
        """Points on the robot's hand geoms and the sponge, for the cup clearance."""
        return self._hand_points

    def _staged(self, scene: Any, ik: PathIK, parts: WipeParts, robot_prefix: str, tool_prefix: str) -> None:
        """What the task reads of the scene it is staged on: where its ``parts`` are, the robot's joint limits (checked
        against the settings), the context's sampling (the table, the cup and the sponge as compiled; checked against
        the robot's reach), the path inverse kinematics ``ik`` and the hand's points."""
        #: where the task's objects and sensors are in its scene
        self.parts = parts
        self.config.check_robot(np.c_[scene.joint_lower, scene.joint_upper])
        clearance, near_patch = self._cup_placement()
        context = self.config.context
        self.context_spec = ContextSpec(context.ranges, table_extent=parts.table_extent, obstacle=self.obstacle,
                                        obstacle_probability=context.obstacle_probability,
                                        obstacle_radius=parts.obstacle_radius, patch_clearance=clearance,
                                        near_patch=near_patch)
        _check_reach(self.context_spec, self.robot)
        #: the path inverse kinematics of the sponge's face centre
        self.ik = ik
        geoms = (*(robot_prefix + n for n in self.robot.hand_geoms), tool_prefix + "sponge")
        self._hand_points = HandPoints(scene.model, scene.qpos_adr, geoms)

    @property
    def simulation_settings(self) -> SimulationSettings:
        """The simulation core's settings of this task
        (:class:`~rdmp_gym.envs.tasks.wiping.simulation.SimulationSettings`)."""
        return SimulationSettings(limit_margin=self.limit_margin, fine_force=self.fine_force,
                                  cup_from_touch=self.cup_from_touch)

    def force_adaptation(self) -> ForceAdaptation:
        """A fresh force controller of this env: the admittance law on the pressing depth (with the learned depth
        profile when ``force_learning`` is on)."""
        if self.force_learning is None:
            return ForceAdaptation(self.adaptation_settings, self.dt)
        return ForceProfileLearning(self.adaptation_settings, self.dt, self.dmp.period, self.dmp.transients[0].phi0,
                                    self.force_learning)

    @property
    def success_joint_accel(self) -> float | None:
        """The peak joint acceleration (rad/s²) that ``is_success`` allows (None: not checked): the robot's limit."""
        return self.reward_settings.max_joint_accel

    # ------------------------------------------------------------------ the plan
    def action_time_weights(self, dmp: RhythmicDMP | None = None, times: np.ndarray | None = None,
                            action_map: ActionMap | None = None) -> np.ndarray:
        """How active each action dimension's parameter is at each control step, ``[T_ctrl, n_action]`` in [0, 1]
        (of the task's own DMP, control times and action map, which the faces run)."""
        weights = self.dmp.param_time_weights(self.times, groups=self.groups, transient=0)[:, self.action_map.free]
        if self._approach:                   # the approach dimension acts where it lifts the path
            lift = lift_profile(self.times, self.dmp.transients[0].length)
            weights = np.c_[weights, lift / lift.max()]
        if "sweep" in self.groups:           # sweep_x, sweep_y act where they move the anchor
            unit = np.c_[COVERING_FIGURE, np.zeros((len(COVERING_FIGURE), self.dmp.n_dims - 2))]
            moved = np.abs(self.dmp.sweep.offsets(self.times, unit[None])[0, :, :2])
            weights = np.c_[weights, moved / np.maximum(moved.max(axis=0), 1e-12)]
        return weights

    def rollout_path(self, theta: np.ndarray, context: Context) -> np.ndarray:
        """Sponge path ``[T_ctrl, 3]`` (nominal table frame) of parameters ``theta`` in ``context``.

        The DMP is anchored at the patch centre and starts at the sponge start with ``start_blend``:
        the offset from the demonstrated start (relative to the anchor) is faded out over the
        transient, so the path starts where the sponge is, keeps the demonstrated approach's shape
        and is the DMP's own periodic pattern from the end of the transient on.
        """
        anchor = np.array([*context.patch_centre, self._anchor_z])
        return self.dmp.rollout_batch(np.asarray(theta, dtype=np.float64)[None], self.times, groups=self.groups,
                                      y0=context.sponge_start, anchor=anchor, start_blend=True)[0]

    def imitation_path(self, context: Context) -> np.ndarray:
        """The imitation's path ``[T_ctrl, 3]`` in ``context`` (``rollout_path(theta0, context)`` to round-off).

        With the parameters fixed, the rollout is affine in the start and the anchor (a linear transformation
        system, a start offset blended out linearly), so the env rolls out the imitation once for a reference
        context and once per unit shift of the 5 context numbers it depends on (start x, y, z; anchor x, y),
        and each context's path is that affine combination: no DMP rollout per episode.
        """
        if self._imitation_paths is None:
            shifts = np.zeros((6, 5))
            shifts[1:] = _IMITATION_SHIFT * np.eye(5)
            anchors = np.c_[shifts[:, 3:], np.full(6, self._anchor_z)]
            theta = np.broadcast_to(self.action_map.theta0, (6, self.action_map.theta0.size))
            paths = self.dmp.rollout_batch(theta, self.times, groups=self.groups, y0=shifts[:, :3], anchor=anchors,
                                           start_blend=True)
            self._imitation_paths = (paths[0], (paths[1:] - paths[0]) / _IMITATION_SHIFT)
        base, unit = self._imitation_paths
        shift = np.r_[context.sponge_start, context.patch_centre]
        return base + np.tensordot(shift, unit, axes=1)

    def solve_path(self, path: np.ndarray, context: Context) -> IKResult:
        """The path IK of a sponge path ``[T, 3]`` (nominal table frame) in ``context``: the joint path the env plans
        for it."""
        pose = TablePose.of(context)
        world = to_world(self.parts, pose, path)
        weight = np.clip(1.0 - (path[:, 2] - self._engage) / 0.05, 0.2, 1.0)
        return self.ik.solve(world, control_frame(self.parts, pose)[1][:, 2], rot_weight=weight)

    def cup(self, context: Context) -> Cup | None:
        """The cup of ``context`` as it stands before the wipe (world frame), or None without one."""
        if not context.obstacle:
            return None
        origin, rot = table_frame(self.parts, TablePose.of(context))
        base = origin + rot @ np.r_[context.obstacle_position, 0.0]
        return Cup(base, self.parts.obstacle_radius, float(base[2] + 2.0 * self.parts.obstacle_half_height))

    # ------------------------------------------------------------------ the judgement
    def statistics(self, trace: WipeTrace, smooth: Smoothness) -> dict[str, Any]:
        """The episode's statistics (:mod:`rdmp_gym.envs.tasks.wiping.info`) from its trace and the smoothness of its
        path."""
        live = np.arange(self.n_steps) < trace.steps
        per = self.periodic & live
        force = trace.contact_force[per]
        low, high = self.force_band
        target = self.reward_settings.target_force
        stats = {
            "coverage": trace.coverage,
            "force_mean": float(force.mean()) if force.size else 0.0,
            "force_sd": float(force.std()) if force.size else 0.0,
            "force_error_mean": float(np.mean(np.abs(force - target))) if force.size else 0.0,
            "force_in_band_fraction": float(np.mean((force >= low) & (force <= high))) if force.size else 0.0,
            "contact_fraction": float(np.mean(force >= self.reward_settings.contact_threshold)) if force.size else 0.0,
            "max_force": float(trace.contact_force[live].max()),
            "max_wrist_force": float(np.abs(trace.wrist_force[live]).max()),
            "impact_force": trace.impact_force,
            "jerk_ratio": smooth.jerk_ratio,
            "peak_joint_accel": float(smooth.joint_accel.max()),
            "arm_collision_fraction": float(np.mean(trace.arm_contact[live])),
            "self_collision_fraction": float(np.mean(trace.self_contact[live])),
            "penetration": trace.penetration,
            "obstacle_touch_steps": int(np.sum(trace.obstacle_contact)),
            "obstacle_shift": float(trace.obstacle_shift.max()),
            "joint_limit_fraction": float(np.mean(trace.at_limit[live])),
            "steps": int(trace.steps),
            "force_trace": trace.contact_force.copy(),
            "dirt_removed_trace": trace.removed.copy(),
        }
        if trace.fine_force is not None:
            stats["fine_force_trace"] = trace.fine_force.copy()
        return stats

    # ------------------------------------------------------------------ the description
    def compose(self, spec: mujoco.MjSpec, robot: RobotDescription, robot_prefix: str, tool_prefix: str) -> None:
        """The sponge tool on the robot's tool mount and the sensors the task reads
        (:func:`~rdmp_gym.envs.tasks.wiping.arena.add_task`), on the task's physics step; the table and the cup stand
        in the wiping arena (:attr:`room`)."""
        spec.option.timestep = self.timestep
        add_task(spec, robot, robot_prefix, tool_prefix)

    def imitation(self) -> RhythmicDMP:
        """The imitation DMP (with the covering sweep where the action has it)."""
        return self.dmp

    def context_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """The observation's bounds ``([13], [13])``."""
        return self.context_spec.bound_low, self.context_spec.bound_high

    def sample_context(self, rng: np.random.Generator, options: Mapping[str, Any] | None) -> Context:
        """A context drawn with ``rng`` (``options`` fix fields; see :mod:`rdmp_gym.envs.tasks.wiping.context`)."""
        return self.context_spec.sample(rng, options)

    def place(self, model: mujoco.MjModel, context: Context) -> None:
        """Tilt and raise the table and stand (or park) the cup for ``context``
        (:func:`~rdmp_gym.envs.tasks.wiping.scene.place_objects`)."""
        place_objects(model, self.parts, context)

    def dirt_cells(self, context: Context) -> np.ndarray:
        """The dirt cells' centres ``[N, 3]`` (world) of ``context`` on the placed table."""
        cells = dirt_grid(context.patch_centre, context.patch_size, self.cell_size)
        origin, rot = table_frame(self.parts, TablePose.of(context))
        return np.c_[cells, np.zeros(len(cells))] @ rot.T + origin

    def plan(self, dmp: RhythmicDMP, theta: np.ndarray, extras: np.ndarray, context: Context, times: np.ndarray,
             table_origin: np.ndarray) -> TaskPlan:
        """The sponge path of ``theta`` in ``context`` (:meth:`rollout_path`, nominal table frame), in the control
        frame (the nominal table origin, the actual tilt)."""
        if dmp is not self.dmp or not np.array_equal(times, self.times):
            raise ValueError("dmp, times: the wiping task plans with its own imitation DMP and control times")
        return TaskPlan(self.rollout_path(theta, context), *control_frame(self.parts, TablePose.of(context)))

    def evaluate(self, path: ToolPath, context: Context, sensor: Mapping[str, slice]) -> Outcome:
        """The reward terms, cost trace, statistics (info) and failure causes of an executed episode, from its
        :class:`WipeRecord` (``path.record``); an episode in which a robot geom penetrated the robot's body or the
        table beyond the limit is void (``info["valid"] = False``, reason ``"penetration"``)."""
        record: WipeRecord = path.record
        trace, smooth = record.trace, record.smooth
        info = self.statistics(trace, smooth)
        traces: dict[str, np.ndarray] = {}
        info["cost_terms"] = traces
        valid = trace.penetration <= record.penetration_limit
        if not valid:
            terms, cost = invalid_reward(trace.penetration / 0.05, self.n_steps, self.reward_weights, traces)
            self.void_coverage(info)
        else:
            terms, cost = wipe_reward(trace, self.periodic, smooth, self.reward_settings, self.reward_weights, traces)
        if not valid:
            logger.debug("penetration %.4f m beyond the limit %.4f m", trace.penetration, record.penetration_limit)
        info["n_cells"] = len(self.dirt_cells(context))
        causes = self.success(info, valid, trace.unstable)[1]
        return Outcome(terms, cost, info, causes, valid=valid, reason="" if valid else "penetration")

    def void_coverage(self, stats: dict[str, Any]) -> None:
        """An episode voided after its simulation (a penetration) reports coverage 0 like one refused before it; its
        simulated coverage goes to ``stats["simulated_coverage"]``."""
        stats["simulated_coverage"], stats["coverage"] = stats["coverage"], 0.0

    def success(self, stats: Mapping[str, Any], valid: bool, unstable: bool) -> tuple[bool, tuple[str, ...]]:
        """``(is_success, causes)`` of an episode's statistics with this version's criteria (:func:`outcome`)."""
        return outcome(stats, valid, unstable, self.success_joint_accel, self.max_jerk_ratio)

    # ------------------------------------------------------------------ execution on the faces
    def stage(self, robot: RobotDescription) -> Stage:
        """The standard stage (:func:`~rdmp_gym.envs.task_scene.standard_stage`: the arena composed with the robot and
        the task, the task's timing, the path IK to the sponge's face centre) with the task's action map (the
        approach and the sweep)."""
        if robot.name != self.robot.name:
            raise ValueError(f"robot: the wiping task was built for {self.robot.name!r}, not {robot.name!r}")
        stage = standard_stage(self, robot, self.action_map)
        parts = WipeParts.read(stage.scene.model, robot, ROBOT_PREFIX, TOOL_PREFIX)
        self._staged(stage.scene, stage.ik, parts, ROBOT_PREFIX, TOOL_PREFIX)
        return stage

    def rest_pose(self, context: Context, plan: TaskPlan, face: Any) -> np.ndarray:
        """The joints with the sponge at the context's start (flat on the table where it is low)."""
        return self.solve_path(context.sponge_start[None], context).q[0]

    def check_params(self, theta: np.ndarray) -> Rejection | None:
        """Parameters whose amplitude leaves the DMP's range are refused (reason ``"r0"``)."""
        violation = self.action_map.r0_violation(theta)
        return Rejection("r0", violation - 1.0) if violation > 0 else None

    def solve(self, plan: TaskPlan, face: Any) -> Solution | Rejection:
        """The path is finite and inside the workspace; its joints (the path IK, :meth:`solve_path`) reach it, with
        the sponge flat on the table where it is low (at most the engage height above it), and move within the
        joint speed limit. With :attr:`cup_clearance` the path is pushed away from the cup first (and checked against
        the workspace again; ``info["clearance_push"]``: the largest push, m)."""
        path = plan.path
        info: dict[str, Any] = {}
        if not np.all(np.isfinite(path)):
            return Rejection("nonfinite_path", 1.0)
        excess = _workspace_excess(path, self.robot.workspace)
        if excess > 0:
            return Rejection("workspace", excess / 0.1)
        context = face.context
        solution = self.solve_path(path, context)
        if self.cup_clearance is not None:
            path, solution = self._clear_cup(path, solution, context, info)
            excess = _workspace_excess(path, self.robot.workspace)
            if excess > 0:
                return Rejection("workspace", excess / 0.1, info)
        flat = path[:, 2] <= self._engage
        bad = (solution.pos_error > self.ik_tolerance[0]) | (flat & (solution.rot_error > self.ik_tolerance[1]))
        if np.any(bad):
            severity = 0.5 * np.mean(bad) + 0.5 * min(1.0, float(solution.pos_error.max()) / 0.1)
            return Rejection("unreachable", severity, info)
        speed = float(np.max(np.abs(np.diff(solution.q, axis=0)))) / self.dt
        if speed > self.max_joint_speed:
            return Rejection("joint_speed", speed / self.max_joint_speed - 1.0, info)
        return Solution(TaskPlan(path, plan.origin, plan.rotation, plan.extras), solution, info)

    def simulate(self, solution: Solution, face: Any, capture: Callable[..., None] | None) -> ToolPath:
        """The simulation core with the wiping hook (:func:`~rdmp_gym.envs.tasks.wiping.simulation.simulate_wipe`) in
        the face's context: the joint targets with the servos' feed-forward, the pressing depth adapted online from
        the wrist force along the control normal, the dirt worn step by step (the frames draw it as worn so far)."""
        path, joints = solution.plan.path, solution.joints
        scene, context = face.scene, face.context
        pose = TablePose.of(context)
        normal = control_frame(self.parts, pose)[1][:, 2]
        plan = face.joint_targets(joints, normal)
        scene.set_arm_state(joints.q[0])
        adaptation = self.force_adaptation()
        dirt = DirtField(self.dirt_cells(context), table_frame(self.parts, pose)[1][:, 2], wear_rate=self.wear_rate,
                         contact_threshold=self.reward_settings.contact_threshold)
        after = None
        if capture is not None:
            capture(-1)

            def after(k: int, dirt_left: Callable[[], np.ndarray]) -> None:
                capture(k, _WornSoFar(dirt_left))

        trace = simulate_wipe(scene, self.parts, plan, path[:, 2], adaptation, dirt, self.frame_skip,
                              self.simulation_settings, callback=after, cup=context.obstacle)
        smooth = self.smoothness(path, joints.q, self.imitation_jerk(context))      # of the path as executed
        return ToolPath(TaskPlan(path, *control_frame(self.parts, pose)), joints.q, np.zeros((0, 0)), np.zeros((0, 0)),
                        np.zeros((0, 0)), trace.sponge_pos, trace.steps, trace.unstable, self.dt, self.frame_skip,
                        smooth.jerk_ratio, float(smooth.joint_accel.max()), self.robot.max_joint_accel,
                        WipeRecord(trace, smooth, self.penetration_limit))

    def invalid(self, reason: str, severity: float, n_steps: int, context: Context) -> Outcome:
        """The invalid-parameter penalty (:func:`~rdmp_gym.envs.tasks.wiping.reward.invalid_reward`) with the void
        statistics of an episode not run (:func:`~rdmp_gym.envs.tasks.wiping.info.void_statistics`)."""
        traces: dict[str, np.ndarray] = {}
        info: dict[str, Any] = {"cost_terms": traces}
        terms, cost = invalid_reward(severity, n_steps, self.reward_weights, traces)
        info.update(void_statistics(n_steps))
        info["n_cells"] = len(self.dirt_cells(context))
        return Outcome(terms, cost, info, ("invalid",), valid=False, reason=reason)

    def render_overlay(self, renderer: SceneRenderer, context: Context, overlay: Any) -> np.ndarray:
        """The frame with the dirt left on the table: as ``overlay`` has worn it (its ``dirt_left() [N]``: the
        episode's record, or the episode so far), all of it before the first step."""
        cells = self.dirt_cells(context)
        dirt = np.ones(len(cells)) if overlay is None else overlay.dirt_left()
        return renderer.render(cells, dirt, 0.5 * self.cell_size, table_frame(self.parts, TablePose.of(context))[1])

    def cycle_state_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """The default's (the sponge's position and its offset from its path), then the dirt left: the fraction of
        the patch's and of each quarter's (x-, y- / x+, y- / x-, y+ / x+, y+ of the patch centre), in [0, 1]."""
        low, high = super().cycle_state_bounds()
        return np.r_[low, np.zeros(5)], np.r_[high, np.ones(5)]

    def cycle_state(self, face: Any, step: int | None, overlay: Any) -> np.ndarray:
        """The default's, then the dirt left (:meth:`cycle_state_bounds`), as worn up to control step ``step``."""
        context = face.context
        cells = dirt_grid(context.patch_centre, context.patch_size, self.cell_size)
        left = np.ones(len(cells)) if overlay is None else overlay.dirt_left()
        quarter = (cells[:, 0] >= context.patch_centre[0]) + 2 * (cells[:, 1] >= context.patch_centre[1])
        shares = [left[quarter == q].mean() if np.any(quarter == q) else 0.0 for q in range(4)]
        return np.r_[super().cycle_state(face, step, overlay), left.mean(), shares]

    def step_book(self, face: Any, reward_every: int) -> WipeStepBook:
        """The wiping task's step interface (:class:`~rdmp_gym.envs.tasks.wiping.step.WipeStepBook`: the canonical
        state, the sponge and the wrist force observed, every reward term grown step by step, so it refuses a given
        ``reward_every``; the target kept in the workspace, the end on a penetration)."""
        return WipeStepBook(face)

    # ------------------------------------------------------------------ the episode's conveniences
    def jerk_measure(self, path: np.ndarray, dt: float) -> float:
        """The jerk of ``path [T, 3]`` with control period ``dt`` that the smoothness compares: per unit of squared
        speed (:meth:`Smoothness.speed_normalised`)."""
        return Smoothness.speed_normalised(path, dt)

    def imitation_jerk(self, context: Context) -> float:
        """The jerk (:meth:`jerk_measure`) of the imitation's path in ``context``, what :meth:`smoothness` compares
        with."""
        return self.jerk_measure(self.imitation_path(context), self.dt)

    def smoothness(self, path: np.ndarray, q: np.ndarray, reference: float) -> Smoothness:
        """Jerk of the commanded path ``[T, 3]`` relative to the imitation's ``reference`` (:meth:`imitation_jerk` in
        the episode's context), and joint accelerations of its joint path ``q [T, n]``."""
        jerk_sq = Smoothness.jerk_squared(path, self.dt)
        ratio = self.jerk_measure(path, self.dt) / max(reference, 1e-12)
        return Smoothness(jerk_sq, ratio, Smoothness.peak_accel(q, self.dt))

    def context_kind(self, observation: np.ndarray) -> str:
        """The kind of the context ``observation [13]`` (:data:`rdmp_gym.envs.tasks.wiping.context.CONTEXT_KINDS`: a
        cup on the approach, a cup beside the patch, no cup on one of the largest patches, no cup), for stratified
        validation."""
        return self.context_spec.kind(Context.from_vector(np.asarray(observation, dtype=np.float64)))

    def executed_path(self, theta: np.ndarray, context: Context) -> np.ndarray:
        """The sponge path ``[T_ctrl, 3]`` (nominal table frame) that an episode in ``context`` executes for parameters
        ``theta``: :meth:`rollout_path`, with :attr:`cup_clearance`'s push where that is on."""
        return self._cleared(self.rollout_path(theta, context), context)

    def execution_path(self, plan: TaskPlan, face: Any) -> np.ndarray:
        """The planned sponge path with :attr:`cup_clearance`'s push where that is on (:meth:`executed_path`), in the
        face's episode context."""
        return self._cleared(plan.path, face.context)

    def _cleared(self, path: np.ndarray, context: Context) -> np.ndarray:
        """``path [T, 3]`` with :attr:`cup_clearance`'s push in ``context`` (as it is without the clearance, without a
        cup, or where the path is refused before the push: not finite, outside the workspace)."""
        if (self.cup_clearance is None or not np.all(np.isfinite(path))
                or _workspace_excess(path, self.robot.workspace) > 0):
            return path
        return self._clear_cup(path, self.solve_path(path, context), context, {})[0]

    def hand_cup_gaps(self, path: np.ndarray, context: Context) -> dict[str, np.ndarray]:
        """``{part: [T]}``: for each part of the hand (fingers, thumb, palm, sponge), the horizontal gap (m)
        between its points below the cup's top and the cup's side at every control step of ``path [T, 3]``
        (nominal table frame) in ``context`` as planned (inverse kinematics, no simulation); inf where the part is
        above the cup. Empty without a cup."""
        cup = self.cup(context)
        if cup is None:
            return {}
        hand = self.hand_points()
        gaps = hand.gaps(self.solve_path(np.asarray(path, dtype=np.float64), context).q, cup)
        return dict(zip(hand.names, gaps.T, strict=True))

    def _clear_cup(self, path: np.ndarray, solution: IKResult, context: Context, info: dict
                   ) -> tuple[np.ndarray, IKResult]:
        """``path [T, 3]`` and its IK solution in ``context`` with :attr:`cup_clearance`'s push (unchanged without a
        cup); records the largest push (m) in ``info["clearance_push"]``."""
        info["clearance_push"] = 0.0
        cup = self.cup(context)
        if cup is None:
            return path, solution
        rotation = control_frame(self.parts, TablePose.of(context))[1]
        path, solution, push = self.cup_clearance.apply(path, solution, partial(self.solve_path, context=context),
                                                        self.hand_points(), cup, rotation, self.dt)
        info["clearance_push"] = push
        return path, solution


@dataclass(frozen=True)
class _WornSoFar:
    """What the frames draw during an episode: the dirt left so far (``worn() [N]``, recomputed on each call)."""

    worn: Callable[[], np.ndarray]

    def dirt_left(self) -> np.ndarray:
        """Dirt left per cell ``[N]`` in [0, 1]."""
        return self.worn()


#: Shift (m) of each context number for the affine basis of :meth:`WipingTask.imitation_path`.
_IMITATION_SHIFT = 0.1
