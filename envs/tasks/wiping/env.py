"""``rdmp_gym/ArmarWipe-v3`` (and v1, v2, ``PandaWipe-v3``): episodic table wiping with a rhythmic DMP.

What each version changes (v2: the travelling pattern, solvable contexts, the smoothness measure, executable
success; v3: the composed scene of any robot and a smooth-path success) is listed in
:mod:`rdmp_gym.envs.tasks.wiping.versions`;
``version`` selects it (default 3, the current task).

One ``step`` is one whole DMP rollout (``terminated=True, truncated=False``):

1. the action ``a in [-1, 1]^n`` becomes DMP parameters ``theta = theta_imitation + scale * a`` (plus, for
   the last dimension, ``approach``, a fixed direction that lifts the approach:
   :mod:`rdmp_gym.envs.tasks.wiping.approach`);
2. the DMP, anchored at the dirt patch centre and started at the sponge start of the context, gives
   the sponge path ``P [T, 3]`` in the table frame (x, y on the table, z above it);
3. the path is checked (finite, inside the workspace, reachable by the IK with the sponge flat on the
   tilted table, joint speeds): an invalid one returns a graded penalty at once, ``info["valid"] = False``;
4. otherwise MuJoCo simulates it at the control rate with differential-IK joint targets and online
   wrist-force adaptation of the pressing depth along the actual table normal (the table height is
   unknown to the controller; its tilt is known from the context); a cup may stand in the approach;
5. the reward sums the terms of :mod:`rdmp_gym.envs.tasks.wiping.reward`, all in ``info["reward_terms"]``, and
   ``info["cost_trace"]`` gives the per-control-step cost for PI² (it sums to ``-reward``;
   ``info["cost_terms"]`` splits it by term);
   ``info["is_success"]``: coverage >= 0.95, force in band >= 90 % of the wiping phase, no collision
   (arm on the table, arm on the robot's body), the cup neither touched nor moved, a valid episode;
   ``info["failure_causes"]`` names the criteria an episode misses (:func:`failure_causes`, empty for a success).

Rendering: ``render_mode="rgb_array"`` renders offscreen with ``mujoco.Renderer``; on a headless
machine set ``MUJOCO_GL=egl`` (or ``osmesa``) before importing mujoco. Because an episode is a single
step, :meth:`ArmarWipeEnv.record_episode` (or ``record_frames=True``) captures frames inside it.
"""

from __future__ import annotations

import logging
import warnings
from collections.abc import Callable, Mapping
from functools import lru_cache
from pathlib import Path
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np

from rdmp_gym import RhythmicDMP, load_dmp, wiping_demonstration
from rdmp_gym.dmp.fitting import FADE_BEFORE_T
from rdmp_gym.dmp.pose import PoseDMP
from rdmp_gym.signals.demonstrations import check_frame

from ...action import ActionMap, checked_action
from ...controller import ForceAdaptation, ForceAdaptationSettings, JointTargetPlan
from ...ik import BodyClearance, IKResult, PathIK
from ...kinematics import ChainKinematics
from ...recording import SceneRenderer, write_video
from ...robots import RobotDescription, get_robot
from ...viewer import HumanViewer
from .approach import approach_direction, lift_profile
from .clearance import Cup, CupClearance, HandPoints
from .context import CONTEXT_FIELDS, Context, ContextSpec
from .context import SIZE as CONTEXT_SIZE
from .coverage import COVERING_FIGURE, covering_sweep, sweep_directions
from .force_learning import ForceProfileLearning, ForceProfileSettings
from .info import void_statistics
from .reward import RewardSettings, RewardWeights, Smoothness, invalid_reward, wipe_reward
from .scene import TablePose, WipeScene, dirt_grid
from .settings import EnvConfig, ForceConfig, RenderConfig, RewardConfig, TaskConfig
from .simulation import DirtField, SimulationSettings, WipeTrace, simulate_wipe
from .versions import TASK_VERSIONS, TaskVersion

__all__ = ["ArmarWipeEnv", "deprecated_v0", "episode_success", "failure_causes", "outcome"]

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


class ArmarWipeEnv(gym.Env):
    """Episodic wiping env; see the module docstring.

    The settings come as one :class:`~rdmp_gym.envs.tasks.wiping.settings.EnvConfig` (``config``), as keywords
    (``gym.make``'s
    way), or both (the keywords change the config); every setting is validated for type and meaning, with an error
    that names it, and :attr:`config` saves to and loads from JSON.

    Args:
        config: all settings at once (default: ``EnvConfig()``).
        robot: the robot, a registered name (``"armar3"``, ``"panda"``) or a ``RobotDescription``
            (:mod:`rdmp_gym.envs.robots`).
        style: synthetic demonstration style 1..4 (1/2 circle, 3/4 figure-eight; 2/4 complex approach).
        demonstration: a user ``rdmp_gym.Demonstration`` ``Y [L, 3]`` in the table frame, in metres: x, y on
            the table, z above its surface (overrides ``style``; checked against the workspace before fitting).
        dmp: a saved DMP (a ``dmp.json`` path, e.g. a run's refined DMP, or a ``RhythmicDMP``) used as the
            imitation without fitting (overrides ``style``; excludes ``demonstration``).
        n_periodic, n_transient, fit_method: DMP fit settings (default the core's ``"trajectory"`` fit: the
            smoothest imitation, half the jerk of ``"ridge"``).
        groups: parameter groups in the action (default periodic weights, transient weights, initial condition,
            amplitude, and ``"approach"``: one dimension that raises or lowers the approach as a whole, see
            :mod:`rdmp_gym.envs.tasks.wiping.approach`; it needs ``"transient"``; v2 adds ``"sweep"``: the anchor
            travels
            over the patch, two action dimensions ``sweep_x``, ``sweep_y``, see
            :mod:`rdmp_gym.envs.tasks.wiping.coverage`).
        scales: per-group action scales (see :mod:`rdmp_gym.envs.action`; ``approach``: lift in m at +1).
        n_periods: periods of the pattern after the transient (default 4 in v1, 7 in v2); ``duration`` (s)
            overrides it.
        control_rate: control frequency (Hz); ``frame_skip`` (physics steps per control step) overrides it.
        timestep: physics step (s; default the model's 2 ms).
        target_force: normal force to hold while wiping (N) (controller and reward).
        force_band: (min, max) normal force (N) that wipes a cell; the max is also the excess-force limit.
        force_sigma: width (N) of the force-closeness reward.
        reward_weights: ``{term: weight}`` overrides (see :mod:`rdmp_gym.envs.tasks.wiping.reward`).
        adaptation: adapt the pressing depth from the wrist force (``False``: feed-forward preload only).
        admittance_gain: depth rate per newton of force error (m/(N s)).
        force_learning: also learn the pressing depth as a periodic function of the DMP's phase and feed it
            forward on the next periods (Gams et al. 2010; :mod:`rdmp_gym.envs.tasks.wiping.force_learning`); ``True``
            or a
            ``ForceProfileSettings``.
        context_ranges: ``{field: (low, high)}`` sampling ranges (see :mod:`rdmp_gym.envs.tasks.wiping.context`).
        obstacle: contexts may put a cup in the approach corridor (``False``: never).
        obstacle_probability: share of drawn contexts with a cup (where one fits).
        cell_size: dirt cell side (m).
        wear_rate: Preston coefficient of the dirt (1/(Pa m); see :mod:`rdmp_gym.envs.tasks.wiping.simulation`).
        penetration_limit: penetration (m) of a robot geom into the robot's body or (other than the
            sponge) into the table beyond which the episode is invalid (reason ``"penetration"``).
        limit_margin: distance to a joint limit (rad) that counts as "at the limit".
        ik_tolerance: (position m, angle rad) IK residuals beyond which a path is unreachable.
        max_joint_speed: joint speed (rad/s) of the planned path beyond which it is invalid (default: the robot's).
        xml_file: a hand-merged scene MJCF (default: the robot's own scene;
        :class:`~rdmp_gym.envs.tasks.wiping.scene.WipeScene`).
        render_mode: ``None``, ``"rgb_array"`` (RGB frames), ``"depth_array"`` (depth in m) or ``"human"``
            (MuJoCo's viewer, following every control step; needs a display); width, height, camera: of the
            rendered frames.
        record_frames: capture frames during every step into :attr:`frames`; frame_stride: every how
            many control steps.
        version: the task version, 1, 2 or 3 (:mod:`rdmp_gym.envs.tasks.wiping.versions`; default 3, the current task as
            ``rdmp_gym/ArmarWipe-v3`` makes it); ``gym.make`` of an id sets its own.
        cup_clearance: execute every path with a clearance term that keeps the hand (fingers, thumb, palm,
            sponge) this many metres from the cup's side (:class:`~rdmp_gym.envs.tasks.wiping.clearance.CupClearance`,
            or one
            given); ``None`` (default): the path as commanded. The reward and the success criteria are the same;
            ``info["clearance_push"]`` gives the largest push of the path (m).
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["human", "rgb_array", "depth_array"], "render_fps": 25}

    def __init__(self, config: EnvConfig | None = None, **settings: Any):
        super().__init__()
        config = EnvConfig.from_kwargs(**settings) if config is None else config.replace(**settings)
        #: every setting of this env (:class:`~rdmp_gym.envs.tasks.wiping.settings.EnvConfig`; saves to and loads from
        #: JSON)
        self.config = config
        #: what this task version changes (see :mod:`rdmp_gym.envs.tasks.wiping.versions`)
        self.task_version: TaskVersion = TASK_VERSIONS[config.task.version]
        #: the robot (:mod:`rdmp_gym.envs.robots`)
        self.robot: RobotDescription = get_robot(config.robot)
        self.render_mode = config.render.render_mode
        self.dmp = self._imitation(config.task)
        self._set_groups(config.task)
        self.scene = WipeScene(self.robot, composed=self.task_version.composed_scene and config.xml_file is None,
                               xml_file=config.xml_file)
        config.check_robot(np.c_[self.scene.joint_lower, self.scene.joint_upper])
        self._set_timing(config)
        self._set_action(config.task)
        self._set_force_and_reward(config.force, config.reward)
        self._set_limits(config.task)
        self.obstacle = config.context.obstacle
        self.context_spec = ContextSpec(config.context.ranges, table_extent=self.scene.table_extent,
                                        obstacle=self.obstacle,
                                        obstacle_probability=config.context.obstacle_probability,
                                        obstacle_radius=self.scene.obstacle_radius,
                                        patch_clearance=self.task_version.patch_clearance(self.scene.sponge_half),
                                        near_patch=self.task_version.pad_clearance)
        _check_reach(self.context_spec, self.robot)
        self.ik = self._path_ik()
        #: the clearance term that keeps the hand away from the cup (None: off)
        clearance = config.task.cup_clearance            # validated by TaskConfig: a margin (m), a term or None
        self.cup_clearance = CupClearance(margin=clearance) if isinstance(clearance, float) else clearance
        self._hand_points = self._hand() if self.cup_clearance is not None else None
        self._lead = self.scene.servo_lead()
        self._engage = self.adaptation_settings.engage_height
        self.action_space = gym.spaces.Box(-1.0, 1.0, shape=(self.action_map.size,), dtype=np.float32)
        self.observation_space = gym.spaces.Box(self.context_spec.bound_low.astype(np.float32),
                                                self.context_spec.bound_high.astype(np.float32),
                                                shape=(CONTEXT_SIZE,), dtype=np.float32)
        self._set_rendering(config.render)
        self.context: Context | None = None
        #: the dirt cells' centres on the actual table, ``[N, 3]`` (world), drawn at reset
        self.dirt_cells = np.zeros((0, 3))
        #: dirt left per cell ``[N]`` in [0, 1] (after the last episode; what ``render`` shows)
        self.dirt_left = np.zeros(0)
        self._imitation_jerk: float | None = None
        self._imitation_paths: tuple[np.ndarray, np.ndarray] | None = None

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

    def _set_groups(self, task: TaskConfig) -> None:
        groups = task.groups
        if groups is None:
            groups = DEFAULT_GROUPS + (("sweep",) if self.task_version.sweep else ())
        #: the DMP parameter groups of theta (the ``approach`` and ``sweep_x``/``sweep_y`` dimensions come after
        #: them in the action; the ``sweep`` via points have none of their own)
        self.groups = tuple(group for group in groups if group != "approach")
        self._approach = "approach" in groups
        # The demonstrated pattern is centred on its anchor; the env re-anchors it at the patch centre,
        # keeping the demonstration's height offset of the anchor (0 for a pattern on the surface).
        self._anchor_z = float(self.dmp.anchor[2])

    def _set_timing(self, config: EnvConfig) -> None:
        """Physics step, control rate and the episode's control steps."""
        model, timing, task = self.scene.model, config.timing, config.task
        if timing.timestep is not None:
            model.opt.timestep = timing.timestep
        self.frame_skip = timing.frame_skip_for(model.opt.timestep)
        self.dt = self.frame_skip * model.opt.timestep
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

    def _set_rendering(self, render: RenderConfig) -> None:
        self.frame_stride = render.frame_stride
        self.metadata = {**self.metadata, "render_fps": max(1, round(self.control_rate / self.frame_stride))}
        self._render_args = (render.width, render.height, render.camera)
        self._renderer: SceneRenderer | None = None
        self._viewer = HumanViewer(self.scene) if render.render_mode == "human" else None
        if render.render_mode in ("rgb_array", "depth_array") or render.record_frames:
            self._renderer = SceneRenderer(self.scene, *self._render_args)
        self.record_frames = render.record_frames
        #: record the sponge-table force at every physics step into ``info["fine_force_trace"]``
        self.fine_force = False
        self.frames: list[np.ndarray] = []

    def _path_ik(self) -> PathIK:
        """The path IK of the robot's chain to the sponge's face centre, with its arm-from-body clearance."""
        scene, robot = self.scene, self.robot
        joints = tuple(scene.name("robot", n) for n in robot.joints)
        geoms = robot.body_clearance
        bodies = () if geoms is None else tuple(scene.name("robot", n) for n in (geoms.box_body, *geoms.capsule_bodies))
        kinematics = ChainKinematics(scene.model, scene.name("tool", "sponge_tcp"), joints, bodies=bodies)
        clearance = None if geoms is None else BodyClearance(
            scene.model, kinematics, scene.name("robot", geoms.box),
            tuple(scene.name("robot", n) for n in geoms.capsules))
        return PathIK(kinematics, robot.posture, robot.mobility, clearance=clearance)

    def _hand(self) -> HandPoints:
        """Points on the robot's hand geoms and the sponge, for the cup clearance."""
        scene = self.scene
        geoms = (*(scene.name("robot", n) for n in self.robot.hand_geoms), scene.name("tool", "sponge"))
        return HandPoints(scene.model, scene.qpos_adr, geoms)

    def force_adaptation(self) -> ForceAdaptation:
        """A fresh force controller of this env: the admittance law on the pressing depth (with the learned depth
        profile when ``force_learning`` is on)."""
        if self.force_learning is None:
            return ForceAdaptation(self.adaptation_settings, self.dt)
        return ForceProfileLearning(self.adaptation_settings, self.dt, self.dmp.period, self.dmp.transients[0].phi0,
                                    self.force_learning)

    @property
    def simulation_settings(self) -> SimulationSettings:
        """The simulation core's settings of this env
        (:class:`~rdmp_gym.envs.tasks.wiping.simulation.SimulationSettings`)."""
        return SimulationSettings(limit_margin=self.limit_margin, fine_force=self.fine_force,
                                  cup_from_touch=self.task_version.cup_from_touch)

    @property
    def success_joint_accel(self) -> float | None:
        """The peak joint acceleration (rad/s²) that ``is_success`` allows (None: not checked, v1)."""
        return self.reward_settings.max_joint_accel if self.task_version.executable_success else None

    # ------------------------------------------------------------------ action <-> parameters
    def action_to_params(self, action: np.ndarray) -> np.ndarray:
        """DMP parameters ``theta [P]`` (float64, groups :attr:`groups`) of an action ``[n_action]`` (clipped to
        [-1, 1] as in :meth:`step`; NaN or a wrong shape raise ValueError). ``n_action = P + 1`` with the
        ``approach`` dimension (last), else P."""
        return self.action_map.to_params(self._check_action(action))

    def params_to_action(self, theta: np.ndarray) -> np.ndarray:
        """An action ``[n_action]`` (float32, unclipped) that maps to ``theta [P]`` (0 in the approach dimension)."""
        return self.action_map.to_action(theta)

    def action_time_weights(self) -> np.ndarray:
        """How active each action dimension's parameter is at each control step, ``[T_ctrl, n_action]`` in [0, 1]."""
        weights = self.dmp.param_time_weights(self.times, groups=self.groups, transient=0)[:, self.action_map.free]
        if self._approach:                   # the approach dimension acts where it lifts the path
            lift = lift_profile(self.times, self.dmp.transients[0].length)
            weights = np.c_[weights, lift / lift.max()]
        if "sweep" in self.groups:           # sweep_x, sweep_y act where they move the anchor
            unit = np.c_[COVERING_FIGURE, np.zeros((len(COVERING_FIGURE), self.dmp.n_dims - 2))]
            moved = np.abs(self.dmp.sweep.offsets(self.times, unit[None])[0, :, :2])
            weights = np.c_[weights, moved / np.maximum(moved.max(axis=0), 1e-12)]
        return weights

    def _check_action(self, action: Any) -> np.ndarray:
        return np.clip(checked_action(action, self.action_space.shape), -1.0, 1.0)

    # ------------------------------------------------------------------ gym API
    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        """Draw a context (``options`` can fix any field; see :mod:`rdmp_gym.envs.tasks.wiping.context`) and put the
        robot at rest with the sponge at the start position."""
        super().reset(seed=seed)
        if options is not None and not isinstance(options, Mapping):
            raise ValueError(f"options: expected a dict, got {type(options).__name__}")
        context = self.context_spec.sample(self.np_random, options)
        self.context = context
        self.scene.set_table(TablePose(context.table_height, *context.table_tilt))
        self.scene.place_obstacle(context.obstacle_position if context.obstacle else None)
        cells = dirt_grid(context.patch_centre, context.patch_size, self.cell_size)
        origin, rot = self.scene.table_frame(actual=True)
        self.dirt_cells = np.c_[cells, np.zeros(len(cells))] @ rot.T + origin
        self.dirt_left = np.ones(len(cells))
        self._imitation_jerk = None
        start = self.solve_path(context.sponge_start[None])
        self.scene.set_arm_state(start.q[0])
        self.frames = []
        return self._observation(), {"context": context.vector()}

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict]:
        """Run one whole wiping episode with the DMP parameters of ``action`` ``[n]`` (clipped to [-1, 1];
        NaN, infinite values or a wrong shape raise ValueError). Always ``terminated=True, truncated=False``."""
        if self.context is None:
            raise RuntimeError("call reset() before step()")
        a = self._check_action(action)
        theta = self.action_map.to_params(a)
        self.frames = []
        reward, info = self._evaluate(theta)
        return self._observation(), reward, True, False, info

    def render(self) -> np.ndarray | None:
        """The current state: RGB frame ``[height, width, 3]`` uint8 (``"rgb_array"``), depth ``[height, width]``
        float32 in m (``"depth_array"``), or None after updating the viewer (``"human"``)."""
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode='rgb_array' to the env")
            return None
        if self._viewer is not None:
            self._viewer.sync()
            return None
        if self.render_mode == "depth_array":
            if self._renderer is None:
                self._renderer = SceneRenderer(self.scene, *self._render_args)
            return self._renderer.render_depth()
        return self._frame()

    def close(self) -> None:
        """Release the renderer (safe to call more than once)."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
        if self._viewer is not None:
            self._viewer.close()

    def record_episode(self, action: np.ndarray, path: str | Path, fps: float | None = None
                       ) -> tuple[np.ndarray, float, bool, bool, dict]:
        """``step(action)`` while capturing frames every ``frame_stride`` control steps, then write them
        to a video at ``path`` (``.mp4`` or ``.gif``). Returns the step's result."""
        recording = self.record_frames
        self.record_frames = True
        try:
            result = self.step(action)
        finally:
            self.record_frames = recording
        write_video(self.frames, path, fps=self.metadata["render_fps"] if fps is None else fps)
        return result

    # ------------------------------------------------------------------ episode
    def context_kind(self, observation: np.ndarray) -> str:
        """The kind of the context ``observation [13]`` (:data:`rdmp_gym.envs.tasks.wiping.context.CONTEXT_KINDS`: a
        cup on the
        approach, a cup beside the patch, no cup on one of the largest patches, no cup), for stratified validation."""
        return self.context_spec.kind(Context.from_vector(np.asarray(observation, dtype=np.float64)))

    def rollout_path(self, theta: np.ndarray) -> np.ndarray:
        """Sponge path ``[T_ctrl, 3]`` (nominal table frame) of parameters ``theta`` in this episode's context.

        The DMP is anchored at the patch centre and starts at the sponge start with ``start_blend``:
        the offset from the demonstrated start (relative to the anchor) is faded out over the
        transient, so the path starts where the sponge is, keeps the demonstrated approach's shape
        and is the DMP's own periodic pattern from the end of the transient on.
        """
        if self.context is None:
            raise RuntimeError("call reset() before rollout_path()")
        anchor = np.array([*self.context.patch_centre, self._anchor_z])
        return self.dmp.rollout_batch(np.asarray(theta, dtype=np.float64)[None], self.times, groups=self.groups,
                                      y0=self.context.sponge_start, anchor=anchor, start_blend=True)[0]

    def imitation_path(self) -> np.ndarray:
        """The imitation's path ``[T_ctrl, 3]`` in this episode's context (``rollout_path(theta0)`` to round-off).

        With the parameters fixed, the rollout is affine in the start and the anchor (a linear transformation
        system, a start offset blended out linearly), so the env rolls out the imitation once for a reference
        context and once per unit shift of the 5 context numbers it depends on (start x, y, z; anchor x, y),
        and each context's path is that affine combination: no DMP rollout per episode.
        """
        if self.context is None:
            raise RuntimeError("call reset() before imitation_path()")
        if self._imitation_paths is None:
            shifts = np.zeros((6, 5))
            shifts[1:] = _IMITATION_SHIFT * np.eye(5)
            anchors = np.c_[shifts[:, 3:], np.full(6, self._anchor_z)]
            theta = np.broadcast_to(self.action_map.theta0, (6, self.action_map.theta0.size))
            paths = self.dmp.rollout_batch(theta, self.times, groups=self.groups, y0=shifts[:, :3], anchor=anchors,
                                           start_blend=True)
            self._imitation_paths = (paths[0], (paths[1:] - paths[0]) / _IMITATION_SHIFT)
        base, unit = self._imitation_paths
        shift = np.r_[self.context.sponge_start, self.context.patch_centre]
        return base + np.tensordot(shift, unit, axes=1)

    def executed_path(self, theta: np.ndarray) -> np.ndarray:
        """The sponge path ``[T_ctrl, 3]`` (nominal table frame) that :meth:`step` executes for parameters
        ``theta``: :meth:`rollout_path`, with :attr:`cup_clearance`'s push where that is on."""
        path = self.rollout_path(theta)
        if (self.cup_clearance is None or not np.all(np.isfinite(path))
                or _workspace_excess(path, self.robot.workspace) > 0):
            return path
        return self._clear_cup(path, self.solve_path(path), {})[0]

    def run_path(self, path: np.ndarray) -> tuple[float, dict]:
        """Simulate a given sponge path ``[T_ctrl, 3]`` (nominal table frame) in this episode's context,
        bypassing the DMP (for tests and hand-made motions). Returns (reward, info)."""
        if self.context is None:
            raise RuntimeError("call reset() before run_path()")
        path = np.asarray(path, dtype=np.float64)
        if path.shape != (self.n_steps, 3):
            raise ValueError(f"path: expected shape ({self.n_steps}, 3), got {path.shape}")
        return self._evaluate(None, path)

    def solve_path(self, path: np.ndarray) -> IKResult:
        """The path IK of a sponge path ``[T, 3]`` (nominal table frame): the joint path the env plans for it."""
        world = self.scene.to_world(path)
        weight = np.clip(1.0 - (path[:, 2] - self._engage) / 0.05, 0.2, 1.0)
        return self.ik.solve(world, self.scene.control_frame()[1][:, 2], rot_weight=weight)

    def _cup(self) -> Cup | None:
        """The episode's cup as it stands before the wipe (world frame), or None without one."""
        if self.context is None or not self.context.obstacle:
            return None
        origin, rot = self.scene.table_frame(actual=True)
        base = origin + rot @ np.r_[self.context.obstacle_position, 0.0]
        return Cup(base, self.scene.obstacle_radius, float(base[2] + 2.0 * self.scene.obstacle_half_height))

    def hand_cup_gaps(self, path: np.ndarray) -> dict[str, np.ndarray]:
        """``{part: [T]}``: for each part of the hand (fingers, thumb, palm, sponge), the horizontal gap (m)
        between its points below the cup's top and the cup's side at every control step of ``path [T, 3]``
        (nominal table frame) as planned (inverse kinematics, no simulation); inf where the part is above the
        cup. Empty without a cup."""
        cup = self._cup()
        if cup is None:
            return {}
        if self._hand_points is None:
            self._hand_points = self._hand()
        gaps = self._hand_points.gaps(self.solve_path(np.asarray(path, dtype=np.float64)).q, cup)
        return dict(zip(self._hand_points.names, gaps.T, strict=True))

    def _clear_cup(self, path: np.ndarray, solution: IKResult, info: dict) -> tuple[np.ndarray, IKResult]:
        """``path [T, 3]`` and its IK solution with :attr:`cup_clearance`'s push (unchanged without a cup);
        records the largest push (m) in ``info["clearance_push"]``."""
        info["clearance_push"] = 0.0
        cup = self._cup()
        if cup is None:
            return path, solution
        path, solution, push = self.cup_clearance.apply(path, solution, self.solve_path, self._hand_points, cup,
                                                        self.scene.control_frame()[1], self.dt)
        info["clearance_push"] = push
        return path, solution

    def smoothness(self, path: np.ndarray, q: np.ndarray) -> Smoothness:
        """Jerk of the commanded path relative to the imitation's in this context (v2: per unit of squared speed,
        :meth:`Smoothness.speed_normalised`), and joint accelerations."""
        jerk_sq = Smoothness.jerk_squared(path, self.dt)
        normalised = self.task_version.speed_normalised_jerk
        measure = Smoothness.speed_normalised if normalised else Smoothness.integrated_jerk
        if self._imitation_jerk is None:
            self._imitation_jerk = measure(self.imitation_path(), self.dt)
        ratio = measure(path, self.dt) / max(self._imitation_jerk, 1e-12)
        return Smoothness(jerk_sq, ratio, Smoothness.peak_accel(q, self.dt))

    def _evaluate(self, theta: np.ndarray | None, path: np.ndarray | None = None) -> tuple[float, dict]:
        info: dict[str, Any] = {"params": None if theta is None else theta.copy()}
        if theta is not None:
            violation = self.action_map.r0_violation(theta)
            if violation > 0:
                return self._invalid(info, "r0", violation - 1.0)
            path = self.rollout_path(theta)
        assert path is not None
        if not np.all(np.isfinite(path)):
            return self._invalid(info, "nonfinite_path", 1.0)
        excess = _workspace_excess(path, self.robot.workspace)
        if excess > 0:
            return self._invalid(info, "workspace", excess / 0.1)
        solution = self.solve_path(path)
        if self.cup_clearance is not None:
            path, solution = self._clear_cup(path, solution, info)
            excess = _workspace_excess(path, self.robot.workspace)
            if excess > 0:
                return self._invalid(info, "workspace", excess / 0.1)
        flat = path[:, 2] <= self._engage
        bad = (solution.pos_error > self.ik_tolerance[0]) | (flat & (solution.rot_error > self.ik_tolerance[1]))
        if np.any(bad):
            severity = 0.5 * np.mean(bad) + 0.5 * min(1.0, float(solution.pos_error.max()) / 0.1)
            return self._invalid(info, "unreachable", severity)
        speed = float(np.max(np.abs(np.diff(solution.q, axis=0)))) / self.dt
        if speed > self.max_joint_speed:
            return self._invalid(info, "joint_speed", speed / self.max_joint_speed - 1.0)

        smooth = self.smoothness(path, solution.q)
        normal = self.scene.control_frame()[1][:, 2]
        plan = JointTargetPlan(solution, self.dt, self._lead, self.scene.joint_lower, self.scene.joint_upper, normal)
        self.scene.set_arm_state(solution.q[0])
        adaptation = self.force_adaptation()
        dirt = DirtField(self.dirt_cells, self.scene.table_frame(actual=True)[1][:, 2], wear_rate=self.wear_rate,
                         contact_threshold=self.reward_settings.contact_threshold)
        callback = self._capture if self.record_frames or self._viewer is not None else None
        self.dirt_left = np.ones(len(self.dirt_cells))
        if callback is not None:
            self.frames.append(self._frame())
        trace = simulate_wipe(self.scene, plan, path[:, 2], adaptation, dirt, self.frame_skip,
                              self.simulation_settings, callback=callback)
        self.dirt_left = trace.dirt
        info.update(self.statistics(trace, smooth))
        traces: dict[str, np.ndarray] = {}
        info["cost_terms"] = traces
        if trace.penetration > self.penetration_limit:
            logger.debug("penetration %.4f m beyond the limit %.4f m", trace.penetration, self.penetration_limit)
            terms, cost = invalid_reward(trace.penetration / 0.05, self.n_steps, self.reward_weights, traces)
            if self.task_version.void_coverage:
                info["simulated_coverage"], info["coverage"] = info["coverage"], 0.0
            return self._finish(info, terms, cost, valid=False, reason="penetration", unstable=trace.unstable)
        terms, cost = wipe_reward(trace, self.periodic, smooth, self.reward_settings, self.reward_weights, traces)
        return self._finish(info, terms, cost, valid=True, reason="", unstable=trace.unstable)

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

    def _invalid(self, info: dict, reason: str, severity: float) -> tuple[float, dict]:
        traces: dict[str, np.ndarray] = {}
        info["cost_terms"] = traces
        terms, cost = invalid_reward(severity, self.n_steps, self.reward_weights, traces)
        info.update(void_statistics(self.n_steps))
        logger.debug("invalid parameters (%s, severity %.3g)", reason, severity)
        return self._finish(info, terms, cost, valid=False, reason=reason, unstable=False)

    def _finish(self, info: dict, terms: dict[str, float], cost: np.ndarray, valid: bool, reason: str,
                unstable: bool) -> tuple[float, dict]:
        reward = sum(terms.values())
        success, causes = outcome(info, valid, unstable, self.success_joint_accel, self.task_version.max_jerk_ratio)
        info.update({"reward_terms": terms, "cost_trace": cost, "valid": valid, "invalid_reason": reason,
                     "unstable": unstable, "is_success": success, "failure_causes": causes,
                     "n_cells": len(self.dirt_cells)})
        return float(reward), info

    # ------------------------------------------------------------------ helpers
    def _observation(self) -> np.ndarray:
        assert self.context is not None
        return self.context.vector().astype(np.float32)

    def _frame(self, dirt: np.ndarray | None = None) -> np.ndarray:
        if self._renderer is None:
            self._renderer = SceneRenderer(self.scene, *self._render_args)
        _, rot = self.scene.table_frame(actual=True)
        return self._renderer.render(self.dirt_cells, self.dirt_left if dirt is None else dirt,
                                     0.5 * self.cell_size, rot)

    def _capture(self, k: int, dirt_left: Callable[[], np.ndarray]) -> None:
        if self._viewer is not None:
            self._viewer.sync()
        if self.record_frames and (k + 1) % self.frame_stride == 0:
            self.frames.append(self._frame(dirt_left()))


#: Shift (m) of each context number for the affine basis of :meth:`ArmarWipeEnv.imitation_path`.
_IMITATION_SHIFT = 0.1


def deprecated_v0(**kwargs: Any) -> ArmarWipeEnv:
    """Entry point of the deprecated ``rdmp_gym/ArmarWipe-v0``: warns and makes v1 without the obstacle.

    v0's reward counted dirt beyond the table edge, touching as wiping and let the arm pass through the
    robot; v1 (:class:`ArmarWipeEnv`) fixes all of it and changes the reward's meaning, hence the new version.
    """
    warnings.warn("rdmp_gym/ArmarWipe-v0 is deprecated and will be removed: its reward could be gamed. It now "
                  "makes rdmp_gym/ArmarWipe-v1 with obstacle=False; use rdmp_gym/ArmarWipe-v3, the current task.",
                  DeprecationWarning, stacklevel=2)
    kwargs.setdefault("obstacle", False)
    kwargs.setdefault("version", 1)
    return ArmarWipeEnv(**kwargs)
