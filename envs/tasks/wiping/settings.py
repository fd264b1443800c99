"""The wiping env's settings as data: typed, frozen, validated objects that save to and load from JSON.

:class:`EnvConfig` groups the settings of :class:`~rdmp_gym.envs.tasks.wiping.env.ArmarWipeEnv` by concern:

==================  ==================================================================================
``robot``           the robot: its registry name (``"armar3"``) or a ``RobotDescription`` (not JSON)
``xml_file``        a hand-merged scene MJCF that replaces the packaged one (versions 1 and 2; None: the packaged)
``task``            :class:`TaskConfig`: version, imitation source, action groups, duration, dirt, limits
``timing``          :class:`TimingConfig`: control rate, frame skip, physics step
``force``           :class:`ForceConfig`: target force, force band, adaptation, force learning
``reward``          :class:`RewardConfig`: term weights
``context``         :class:`ContextConfig`: sampling ranges, the cup
``render``          :class:`RenderConfig`: render mode, frame size, camera, recording
==================  ==================================================================================

Every object checks its values when it is made, for their type and for their meaning: a setting that would make
the task meaningless (a target force outside the force band, a dirt cell as large as the patch, a joint-limit
margin that puts every step at the limit, a control rate at which no path is reachable) raises ``ValueError``
naming the argument and what is expected; a value of the wrong type raises :class:`SettingTypeError` (a
``TypeError`` and a ``ValueError``). The defaults are the env's own::

    from rdmp_gym.envs.tasks.wiping.settings import EnvConfig

    config = EnvConfig.from_kwargs(version=2, target_force=15.0)   # the env's keyword arguments
    config.save("run/env_config.json")
    assert EnvConfig.load("run/env_config.json") == config
    config.to_kwargs()["target_force"]                             # 15.0: back to keyword arguments

JSON holds numbers, strings, lists and mappings only: a live ``Demonstration``, ``RhythmicDMP`` or
``RobotDescription`` is refused by name (save the DMP with :func:`rdmp_gym.save_dmp` and give its path as ``dmp``;
register the robot, :func:`rdmp_gym.envs.robots.register_robot`, and give its name); a
:class:`~rdmp_gym.envs.tasks.wiping.clearance.CupClearance` or a
:class:`~rdmp_gym.envs.tasks.wiping.force_learning.ForceProfileSettings` is stored as the mapping of its fields.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

from rdmp_gym import Demonstration, RhythmicDMP
from rdmp_gym.dmp.fitting import FIT_METHODS
from rdmp_gym.validation import (
    SettingTypeError,
    check_flag,
    check_integer,
    check_mapping,
    check_number,
    check_optional_number,
    check_pair,
    check_path,
    is_number,
)

from ...robots import RobotDescription
from .clearance import CupClearance
from .context import ContextSpec
from .force_learning import ForceProfileSettings
from .reward import COVERAGE_TIMINGS, RewardWeights
from .versions import TASK_VERSIONS

__all__ = [
    "ENV_KWARGS",
    "ContextConfig",
    "EnvConfig",
    "ForceConfig",
    "RenderConfig",
    "RewardConfig",
    "SettingTypeError",
    "TaskConfig",
    "TimingConfig",
]

#: The physics step (s) of the packaged scenes (the arena's ``<option timestep>``), used to check a control rate
#: when no ``timestep`` is given; the env checks again against its model (:meth:`TimingConfig.frame_skip_for`).
DEFAULT_TIMESTEP = 0.002
#: The lowest control rate (Hz): below it the IK's joint steps between control steps make every path unreachable.
MIN_CONTROL_RATE = 20.0
#: The largest dirt cell, as a share of the smallest patch side that the context can draw (two cells a side).
MAX_CELL_FRACTION = 0.5
#: The largest margin (m) of the cup-clearance term: more pushes the sponge off the patch.
MAX_CUP_CLEARANCE = 0.05
#: The largest joint-limit margin (rad); a robot also needs it below a quarter of its narrowest joint range.
MAX_LIMIT_MARGIN = 0.5
#: The share of the narrowest joint range that the joint-limit margin may take (:meth:`EnvConfig.check_robot`).
MAX_LIMIT_MARGIN_SHARE = 0.25
#: Render modes of the env.
RENDER_MODES = ("human", "rgb_array", "depth_array")
#: The version of the JSON layout written by :meth:`EnvConfig.to_dict`.
FORMAT_VERSION = 1


# ---------------------------------------------------------------------------------------------- checks
def _set(obj: object, name: str, value: object) -> None:
    object.__setattr__(obj, name, value)


# ---------------------------------------------------------------------------------------------- the groups
@dataclass(frozen=True)
class TaskConfig:
    """What the task is: its version, the imitation, the action, the episode's length, the dirt and the limits.

    Attributes:
        version: the task version (:mod:`rdmp_gym.envs.tasks.wiping.versions`; default the current, 3;
            ``gym.make`` of an id sets its own).
        style: synthetic demonstration style 1..4 (used when neither ``demonstration`` nor ``dmp`` is given).
        demonstration: a ``rdmp_gym.Demonstration`` with 3 dimensions (x, y, z in the table frame) to fit (not JSON).
        dmp: a ``dmp.json`` path (or a ``RhythmicDMP``, which is not JSON) used as the imitation without fitting.
        n_periodic, n_transient: basis functions of the fit (integers >= 1).
        fit_method: one of :data:`rdmp_gym.dmp.fitting.FIT_METHODS`.
        groups: the action's parameter groups (None: the version's default; a name or a tuple of names).
        scales: ``{group: fraction}`` action scales (finite numbers > 0), or None.
        n_periods: periods after the transient (None: the version's default); ``duration`` (s) overrides it.
        duration: episode length (s), or None.
        cell_size: dirt cell side (m), at most half the smallest patch side the context can draw.
        wear_rate: Preston coefficient of the dirt (1/(Pa m)).
        penetration_limit: penetration (m) beyond which an episode is invalid.
        limit_margin: distance to a joint limit (rad) that counts as "at the limit": >= 0 and below
            :data:`MAX_LIMIT_MARGIN` (and a quarter of the robot's narrowest joint range, :meth:`check_robot`).
        ik_tolerance: (position m, angle rad) IK residuals beyond which a path is unreachable.
        max_joint_speed: joint speed (rad/s) of the planned path beyond which it is invalid (None: the robot's).
        cup_clearance: the hand's clearance margin from the cup (m, in (0, :data:`MAX_CUP_CLEARANCE`]), a
            ``CupClearance`` with such a margin, or None (off).
    """

    version: int = 3
    style: int = 1
    demonstration: Demonstration | None = None
    dmp: str | RhythmicDMP | None = None
    n_periodic: int = 40
    n_transient: int = 40
    fit_method: str = "trajectory"
    groups: tuple[str, ...] | None = None
    scales: dict[str, float] | None = None
    n_periods: float | None = None
    duration: float | None = None
    cell_size: float = 0.01
    wear_rate: float = 2.0e-3
    penetration_limit: float = 0.005
    limit_margin: float = 0.02
    ik_tolerance: tuple[float, float] = (0.005, float(np.deg2rad(5.0)))
    max_joint_speed: float | None = None
    cup_clearance: float | CupClearance | None = None

    def __post_init__(self) -> None:
        if not is_number(self.version) or self.version not in TASK_VERSIONS:
            raise ValueError(f"version: expected one of {sorted(TASK_VERSIONS)}, got {self.version!r}")
        _set(self, "version", int(self.version))
        if not is_number(self.style) or self.style not in (1, 2, 3, 4):
            raise ValueError(f"style: expected 1, 2, 3 or 4, got {self.style!r}")
        _set(self, "style", int(self.style))
        if self.demonstration is not None:
            if not isinstance(self.demonstration, Demonstration):
                raise SettingTypeError("demonstration: expected an rdmp_gym.Demonstration, "
                                f"got {type(self.demonstration).__name__}")
            if self.demonstration.n_dims != 3:
                raise ValueError("demonstration: expected 3 dimensions (x, y, z in the table frame), "
                                 f"got {self.demonstration.n_dims}")
        if self.dmp is not None:
            if self.demonstration is not None:
                raise ValueError("dmp: give either dmp or demonstration, not both")
            if isinstance(self.dmp, RhythmicDMP):
                if self.dmp.n_dims != 3:
                    raise ValueError(f"dmp: expected 3 dimensions (x, y, z in the table frame), got {self.dmp.n_dims}")
            elif isinstance(self.dmp, (str, Path)) and str(self.dmp):
                _set(self, "dmp", str(self.dmp))
            else:
                raise SettingTypeError(f"dmp: expected a dmp.json path or a RhythmicDMP, got {type(self.dmp).__name__}")
        _set(self, "n_periodic", check_integer(self.n_periodic, "n_periodic"))
        _set(self, "n_transient", check_integer(self.n_transient, "n_transient"))
        if self.fit_method not in FIT_METHODS:
            raise ValueError(f"fit_method: expected one of {FIT_METHODS}, got {self.fit_method!r}")
        if self.groups is not None:
            groups = (self.groups,) if isinstance(self.groups, str) else self.groups
            if not isinstance(groups, Iterable) or isinstance(groups, Mapping):
                raise SettingTypeError(f"groups: expected a group name or a sequence of names, got {self.groups!r}")
            groups = tuple(groups)
            if not groups or not all(isinstance(g, str) and g for g in groups):
                raise ValueError(f"groups: expected one or more group names, got {self.groups!r}")
            _set(self, "groups", groups)
        if self.scales is not None:
            scales = check_mapping(self.scales, "scales", "{group: fraction} or None")
            _set(self, "scales", {key: check_number(value, f"scales: {key}", low=0.0, what=" (an action scale > 0)")
                                  for key, value in scales.items()})
        _set(self, "n_periods", check_optional_number(self.n_periods, "n_periods", low=0.0))
        _set(self, "duration", check_optional_number(self.duration, "duration", low=0.0, what=" (s)"))
        _set(self, "cell_size", check_number(self.cell_size, "cell_size", low=0.0, what=" (m)"))
        _set(self, "wear_rate", check_number(self.wear_rate, "wear_rate", low=0.0))
        _set(self, "penetration_limit", check_number(self.penetration_limit, "penetration_limit", low=0.0, what=" (m)"))
        margin = check_number(self.limit_margin, "limit_margin", low=0.0, strict_low=False, what=" (rad)")
        if margin >= MAX_LIMIT_MARGIN:
            raise ValueError(f"limit_margin: expected a margin below {MAX_LIMIT_MARGIN} rad (the distance to a joint "
                             f"limit that counts as at the limit; with {margin:g} every step is at a limit), "
                             f"got {self.limit_margin!r}")
        _set(self, "limit_margin", margin)
        tolerance = check_pair(self.ik_tolerance, "ik_tolerance", "(position m, angle rad)")
        if min(tolerance) <= 0.0:
            raise ValueError(f"ik_tolerance: expected (position m, angle rad) > 0, got {self.ik_tolerance!r}")
        _set(self, "ik_tolerance", tolerance)
        _set(self, "max_joint_speed", check_optional_number(self.max_joint_speed, "max_joint_speed", low=0.0,
                                                       what=" (rad/s)"))
        _set(self, "cup_clearance", _cup_clearance(self.cup_clearance))

    def check_robot(self, joint_ranges: np.ndarray) -> None:
        """Check the settings that depend on the robot: ``limit_margin`` at most a quarter of the narrowest of
        ``joint_ranges [n, 2]`` (rad; low, high per controlled joint). Raises ValueError naming the setting."""
        ranges = np.asarray(joint_ranges, dtype=np.float64)
        if ranges.ndim != 2 or ranges.shape[1] != 2 or ranges.shape[0] == 0 or not np.all(np.isfinite(ranges)):
            raise ValueError(f"joint_ranges: expected [n, 2] finite (low, high) per joint, got shape {ranges.shape}")
        narrowest = float(np.min(ranges[:, 1] - ranges[:, 0]))
        if self.limit_margin > MAX_LIMIT_MARGIN_SHARE * narrowest:
            raise ValueError(f"limit_margin: expected at most a quarter of the robot's narrowest joint range "
                             f"({narrowest:.3g} rad), i.e. <= {MAX_LIMIT_MARGIN_SHARE * narrowest:.3g} rad, "
                             f"got {self.limit_margin!r}")


def _cup_clearance(value: object) -> float | CupClearance | None:
    if value is None:
        return None
    margin = value.margin if isinstance(value, CupClearance) else value
    if not isinstance(value, CupClearance) and not is_number(value):
        raise SettingTypeError(f"cup_clearance: expected None, a margin in metres or a CupClearance, got {value!r}")
    number = check_number(margin, "cup_clearance", low=0.0, what=" (margin, m)")
    if number > MAX_CUP_CLEARANCE:
        raise ValueError(f"cup_clearance: expected a margin in (0, {MAX_CUP_CLEARANCE}] m (a larger one pushes the "
                         f"sponge off the patch), got {margin!r}")
    return value if isinstance(value, CupClearance) else number


@dataclass(frozen=True)
class TimingConfig:
    """The control and physics rates.

    Attributes:
        control_rate: control frequency (Hz): at least :data:`MIN_CONTROL_RATE` and at most the physics rate
            (1 / ``timestep``); ``frame_skip`` overrides it.
        frame_skip: physics steps per control step (an integer >= 1), or None (from ``control_rate``).
        timestep: physics step (s), or None (the model's: :data:`DEFAULT_TIMESTEP` in the packaged scenes).
    """

    control_rate: float = 100.0
    frame_skip: int | None = None
    timestep: float | None = None

    def __post_init__(self) -> None:
        _set(self, "timestep", check_optional_number(self.timestep, "timestep", low=0.0, what=" (s)"))
        _set(self, "control_rate", check_number(self.control_rate, "control_rate", low=0.0, what=" (Hz)"))
        if self.frame_skip is not None:
            _set(self, "frame_skip", check_integer(self.frame_skip, "frame_skip"))
        self._check_rate(DEFAULT_TIMESTEP if self.timestep is None else self.timestep)

    def _check_rate(self, timestep: float) -> None:
        if self.frame_skip is not None:
            rate = 1.0 / (self.frame_skip * timestep)
            if rate < MIN_CONTROL_RATE:
                raise ValueError(f"frame_skip: expected at most {int(1.0 / (MIN_CONTROL_RATE * timestep))} physics "
                                 f"steps of {timestep:g} s per control step (a control rate >= {MIN_CONTROL_RATE:g} "
                                 f"Hz), got {self.frame_skip!r} ({rate:.3g} Hz)")
            return
        if self.control_rate < MIN_CONTROL_RATE:
            raise ValueError(f"control_rate: expected at least {MIN_CONTROL_RATE:g} Hz (below it no path is "
                             f"reachable), got {self.control_rate!r}")
        if self.control_rate * timestep > 1.0 + 1e-9:
            raise ValueError(f"control_rate: expected at most the physics rate {1.0 / timestep:g} Hz (1 / timestep), "
                             f"got {self.control_rate!r}")

    def frame_skip_for(self, model_timestep: float) -> int:
        """Physics steps per control step on a model whose step is ``model_timestep`` (s; ``timestep`` replaces it
        when given), checked as in ``__post_init__`` (the env's own rule: ``round(1 / (rate * timestep))``)."""
        timestep = check_number(model_timestep, "timestep", low=0.0) if self.timestep is None else self.timestep
        self._check_rate(timestep)
        if self.frame_skip is not None:
            return self.frame_skip
        return max(1, round(1.0 / (self.control_rate * timestep)))


@dataclass(frozen=True)
class ForceConfig:
    """The contact force: what to hold, what wipes, how the pressing depth follows the wrist force.

    Attributes:
        target_force: the normal force (N) to hold while wiping: inside ``force_band`` (else no step is a success).
        force_band: (min, max) normal force (N) that wipes a cell, ``0 <= min < max``; the max is the excess limit.
        force_sigma: width (N) of the force-closeness reward (> 0).
        adaptation: adapt the pressing depth from the wrist force (True or False).
        admittance_gain: depth rate per newton of force error (m/(N s), >= 0).
        force_learning: also learn the pressing depth over the periods: True, False or a ``ForceProfileSettings``.
    """

    target_force: float = 18.0
    force_band: tuple[float, float] = (5.0, 60.0)
    force_sigma: float = 6.0
    adaptation: bool = True
    admittance_gain: float = 0.02
    force_learning: bool | ForceProfileSettings = False

    def __post_init__(self) -> None:
        band = check_pair(self.force_band, "force_band", "(min, max) in N")
        if not 0.0 <= band[0] < band[1]:
            raise ValueError(f"force_band: expected (min, max) with 0 <= min < max, got {self.force_band!r}")
        _set(self, "force_band", band)
        target = check_number(self.target_force, "target_force", low=0.0, what=" (N)")
        if not band[0] < target < band[1]:
            raise ValueError(f"target_force: expected a force inside force_band ({band[0]:g}, {band[1]:g}) N (outside "
                             f"it no episode can hold the force in the band), got {self.target_force!r}")
        _set(self, "target_force", target)
        _set(self, "force_sigma", check_number(self.force_sigma, "force_sigma", low=0.0, what=" (N)"))
        _set(self, "adaptation", check_flag(self.adaptation, "adaptation"))
        _set(self, "admittance_gain", check_number(self.admittance_gain, "admittance_gain", low=0.0, strict_low=False,
                                              what=" (m/(N s))"))
        if isinstance(self.force_learning, (bool, np.bool_)):
            _set(self, "force_learning", bool(self.force_learning))
        elif not isinstance(self.force_learning, ForceProfileSettings):
            raise SettingTypeError("force_learning: expected True, False or a ForceProfileSettings, "
                            f"got {type(self.force_learning).__name__}")


@dataclass(frozen=True)
class RewardConfig:
    """The reward's term weights, and when the per-step cost trace books the coverage.

    Attributes:
        weights: ``{term: weight}`` overrides of :class:`~rdmp_gym.envs.tasks.wiping.reward.RewardWeights`
            (finite numbers >= 0), or None (the defaults).
        coverage_timing: where ``info["cost_trace"]`` books the coverage term: ``"end"`` (its whole value at the
            last step) or ``"wiped"`` (each step the dirt it removed, as the step twin rewards it). The return is
            the same either way (up to rounding); learners that credit time (PI², ``cpi2``, ``bbrl``,
            ``bbrl_segments``) see when the coverage was earned only with ``"wiped"``.
    """

    weights: dict[str, float] | None = None
    coverage_timing: str = "end"

    def __post_init__(self) -> None:
        if self.coverage_timing not in COVERAGE_TIMINGS:
            raise ValueError(f"coverage_timing: expected one of {list(COVERAGE_TIMINGS)}, "
                             f"got {self.coverage_timing!r}")
        if self.weights is None:
            return
        if isinstance(self.weights, RewardWeights):
            weights = dataclasses.asdict(self.weights)
        else:
            weights = check_mapping(self.weights, "reward_weights", "{term: weight} or None")
        weights = {key: check_number(value, f"reward_weights: {key}", low=0.0, strict_low=False)
                   for key, value in weights.items()}
        RewardWeights.from_mapping(weights)                 # unknown terms raise, naming reward_weights
        _set(self, "weights", weights)


@dataclass(frozen=True)
class ContextConfig:
    """What ``reset`` draws (:mod:`rdmp_gym.envs.tasks.wiping.context`).

    Attributes:
        ranges: ``{field: (low, high)}`` sampling ranges of the drawn fields (each a number or one per component,
            within the field's bounds), or None (the defaults).
        obstacle: whether contexts may have a cup (True or False).
        obstacle_probability: share of drawn contexts with a cup, in [0, 1].
    """

    ranges: dict[str, tuple] | None = None
    obstacle: bool = True
    obstacle_probability: float = 0.75

    def __post_init__(self) -> None:
        if self.ranges is not None:
            ranges = check_mapping(self.ranges, "context_ranges", "{field: (low, high)} or None")
            _set(self, "ranges", {key: _range(value, key) for key, value in ranges.items()})
        _set(self, "obstacle", check_flag(self.obstacle, "obstacle"))
        _set(self, "obstacle_probability", check_number(self.obstacle_probability, "obstacle_probability", low=0.0,
                                                   strict_low=False, high=1.0, what=" in [0, 1]"))
        self.spec()                                   # fields, bounds, low <= high: raise naming context_ranges

    def spec(self) -> ContextSpec:
        """The sampling ranges on an unbounded table (their bounds checked; the env checks the table)."""
        inf = float("inf")
        return ContextSpec(self.ranges, table_extent=(-inf, inf, -inf, inf), obstacle=False)

    def smallest_patch(self) -> float:
        """The smallest patch side (m) that the ranges can draw."""
        return float(np.min(self.spec().low[5:7]))


def _range(value: object, key: str) -> tuple:
    """A ``(low, high)`` range as a tuple of two numbers or of two tuples of numbers (exact in JSON)."""
    name = f"context_ranges: {key}"
    if isinstance(value, (str, bytes, Mapping)) or not isinstance(value, Iterable):
        raise SettingTypeError(f"{name}: expected (low, high), got {value!r}")
    ends = tuple(value)
    if len(ends) != 2:
        raise ValueError(f"{name}: expected (low, high), got {value!r}")
    out = []
    for end in ends:
        if is_number(end):
            out.append(check_number(end, name))
            continue
        try:
            array = np.asarray(end)
        except (TypeError, ValueError) as error:                          # ragged
            raise ValueError(f"{name}: expected (low, high) of numbers, got {value!r}") from error
        if array.ndim != 1 or array.dtype.kind not in "iuf":
            raise SettingTypeError(f"{name}: expected (low, high) of numbers, got {value!r}")
        out.append(tuple(check_number(x.item(), name) for x in array))
    return tuple(out)


@dataclass(frozen=True)
class RenderConfig:
    """Rendering and frame recording.

    Attributes:
        render_mode: None, ``"rgb_array"``, ``"depth_array"`` or ``"human"``.
        width, height: frame size in pixels (integers >= 1).
        camera: the camera's name, or None (the free camera).
        record_frames: capture frames during every step (True or False).
        frame_stride: every how many control steps a frame is captured (an integer >= 1).
    """

    render_mode: str | None = None
    width: int = 480
    height: int = 480
    camera: str | None = "front"
    record_frames: bool = False
    frame_stride: int = 4

    def __post_init__(self) -> None:
        if self.render_mode is not None and self.render_mode not in RENDER_MODES:
            raise ValueError(f"render_mode: expected None or one of {list(RENDER_MODES)}, got {self.render_mode!r}")
        _set(self, "width", check_integer(self.width, "width"))
        _set(self, "height", check_integer(self.height, "height"))
        if self.camera is not None and not isinstance(self.camera, str):
            raise SettingTypeError(f"camera: expected a camera name or None, got {self.camera!r}")
        _set(self, "record_frames", check_flag(self.record_frames, "record_frames"))
        _set(self, "frame_stride", check_integer(self.frame_stride, "frame_stride"))


# ---------------------------------------------------------------------------------------------- the whole
#: The env's keyword arguments, in the order of its signature, and where each lives: (group, field).
_KWARGS: dict[str, tuple[str | None, str]] = {
    "style": ("task", "style"),
    "demonstration": ("task", "demonstration"),
    "dmp": ("task", "dmp"),
    "n_periodic": ("task", "n_periodic"),
    "n_transient": ("task", "n_transient"),
    "fit_method": ("task", "fit_method"),
    "groups": ("task", "groups"),
    "scales": ("task", "scales"),
    "n_periods": ("task", "n_periods"),
    "duration": ("task", "duration"),
    "control_rate": ("timing", "control_rate"),
    "frame_skip": ("timing", "frame_skip"),
    "timestep": ("timing", "timestep"),
    "target_force": ("force", "target_force"),
    "force_band": ("force", "force_band"),
    "force_sigma": ("force", "force_sigma"),
    "reward_weights": ("reward", "weights"),
    "coverage_timing": ("reward", "coverage_timing"),
    "adaptation": ("force", "adaptation"),
    "admittance_gain": ("force", "admittance_gain"),
    "force_learning": ("force", "force_learning"),
    "context_ranges": ("context", "ranges"),
    "obstacle": ("context", "obstacle"),
    "obstacle_probability": ("context", "obstacle_probability"),
    "cell_size": ("task", "cell_size"),
    "wear_rate": ("task", "wear_rate"),
    "penetration_limit": ("task", "penetration_limit"),
    "limit_margin": ("task", "limit_margin"),
    "ik_tolerance": ("task", "ik_tolerance"),
    "max_joint_speed": ("task", "max_joint_speed"),
    "xml_file": (None, "xml_file"),
    "render_mode": ("render", "render_mode"),
    "width": ("render", "width"),
    "height": ("render", "height"),
    "camera": ("render", "camera"),
    "record_frames": ("render", "record_frames"),
    "frame_stride": ("render", "frame_stride"),
    "version": ("task", "version"),
    "cup_clearance": ("task", "cup_clearance"),
    "robot": (None, "robot"),
}
#: The keyword arguments of :class:`~rdmp_gym.envs.tasks.wiping.env.ArmarWipeEnv`, in the order of its signature.
ENV_KWARGS: tuple[str, ...] = tuple(_KWARGS)
_GROUPS: dict[str, type] = {}            # filled below the class: name -> config class


@dataclass(frozen=True)
class EnvConfig:
    """All settings of the wiping env, grouped (see the module docstring); ``EnvConfig()`` is the env's defaults.

    Attributes:
        robot: the robot's registry name (:mod:`rdmp_gym.envs.robots`) or its ``RobotDescription``.
        xml_file: a hand-merged scene MJCF path that replaces the packaged one (versions 1 and 2), or None.
        task, timing, force, reward, context, render: the groups.
    """

    robot: str | RobotDescription = "armar3"
    xml_file: str | None = None
    task: TaskConfig = field(default_factory=TaskConfig)
    timing: TimingConfig = field(default_factory=TimingConfig)
    force: ForceConfig = field(default_factory=ForceConfig)
    reward: RewardConfig = field(default_factory=RewardConfig)
    context: ContextConfig = field(default_factory=ContextConfig)
    render: RenderConfig = field(default_factory=RenderConfig)

    def __post_init__(self) -> None:
        if not isinstance(self.robot, RobotDescription) and not (isinstance(self.robot, str) and self.robot):
            raise SettingTypeError(f"robot: expected a robot's name or a RobotDescription, got {self.robot!r}")
        _set(self, "xml_file", check_path(self.xml_file, "xml_file"))
        for name, cls in _GROUPS.items():
            if not isinstance(getattr(self, name), cls):
                raise SettingTypeError(f"{name}: expected a {cls.__name__}, got {type(getattr(self, name)).__name__}")
        smallest = self.context.smallest_patch()
        if self.task.cell_size > MAX_CELL_FRACTION * smallest:
            raise ValueError(f"cell_size: expected at most {MAX_CELL_FRACTION:g} x the smallest patch side the "
                             f"context can draw ({smallest:g} m), i.e. <= {MAX_CELL_FRACTION * smallest:g} m (a "
                             f"patch of one cell makes coverage meaningless), got {self.task.cell_size!r}")

    # ------------------------------------------------------------------ keyword arguments
    @classmethod
    def from_kwargs(cls, **kwargs: Any) -> EnvConfig:
        """The settings from the env's keyword arguments (:data:`ENV_KWARGS`); the others default. An unknown
        keyword raises :class:`SettingTypeError` (a TypeError) naming it."""
        return cls().replace(**kwargs)

    def replace(self, **kwargs: Any) -> EnvConfig:
        """A copy with some of the env's keyword arguments (:data:`ENV_KWARGS`) changed, validated."""
        unknown = [key for key in kwargs if key not in _KWARGS]
        if unknown:
            raise SettingTypeError(f"unknown env setting(s) {unknown}; expected some of {list(ENV_KWARGS)}")
        top: dict[str, Any] = {key: kwargs[key] for key in ("robot", "xml_file") if key in kwargs}
        for group in _GROUPS:
            changes = {_KWARGS[key][1]: value for key, value in kwargs.items()
                       if key in _KWARGS and _KWARGS[key][0] == group}
            if changes:
                top[group] = dataclasses.replace(getattr(self, group), **changes)
        return dataclasses.replace(self, **top)

    def to_kwargs(self) -> dict[str, Any]:
        """The env's keyword arguments (:data:`ENV_KWARGS`, in the order of its signature)."""
        return {key: getattr(self if group is None else getattr(self, group), name)
                for key, (group, name) in _KWARGS.items()}

    def check_robot(self, joint_ranges: np.ndarray) -> None:
        """Check the settings that depend on the robot (see :meth:`TaskConfig.check_robot`)."""
        self.task.check_robot(joint_ranges)

    # ------------------------------------------------------------------ JSON
    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready mapping (numbers, strings, lists, mappings). Raises ValueError naming ``demonstration``,
        ``dmp`` or ``robot`` when one is a live object: save the DMP (:func:`rdmp_gym.save_dmp`) and give its path;
        register the robot and give its name."""
        if isinstance(self.robot, RobotDescription):
            raise ValueError(f"robot: a RobotDescription object cannot be stored as JSON; register it "
                             f"(rdmp_gym.envs.robots.register_robot) and give its name ({self.robot.name!r}) as robot")
        if self.task.demonstration is not None:
            raise ValueError("demonstration: a Demonstration object cannot be stored as JSON; fit it "
                             "(rdmp_gym.RhythmicDMP.fit), save the DMP (rdmp_gym.save_dmp) and give its path as dmp")
        if isinstance(self.task.dmp, RhythmicDMP):
            raise ValueError("dmp: a RhythmicDMP object cannot be stored as JSON; save it (rdmp_gym.save_dmp) and "
                             "give its path as dmp")
        out: dict[str, Any] = {"format_version": FORMAT_VERSION, "robot": self.robot, "xml_file": self.xml_file}
        for group in _GROUPS:
            out[group] = {f.name: _to_json(getattr(getattr(self, group), f.name))
                          for f in fields(getattr(self, group))}
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> EnvConfig:
        """Inverse of :meth:`to_dict` (missing entries default; unknown ones raise ValueError naming them)."""
        data = check_mapping(data, "config", "a mapping (EnvConfig.to_dict)")
        version = data.pop("format_version", FORMAT_VERSION)
        if version != FORMAT_VERSION:
            raise ValueError(f"format_version: expected {FORMAT_VERSION}, got {version!r}")
        unknown = sorted(set(data) - {"robot", "xml_file", *_GROUPS})
        if unknown:
            raise ValueError(f"config: unknown entries {unknown}; expected some of "
                             f"{['format_version', 'robot', 'xml_file', *_GROUPS]}")
        top: dict[str, Any] = {key: data[key] for key in ("robot", "xml_file") if key in data}
        for group, group_cls in _GROUPS.items():
            if group not in data:
                continue
            values = check_mapping(data[group], group, f"a mapping of {group_cls.__name__}'s fields")
            names = {f.name for f in fields(group_cls)}
            bad = sorted(set(values) - names)
            if bad:
                raise ValueError(f"{group}: unknown entries {bad}; expected some of {sorted(names)}")
            top[group] = group_cls(**{key: _from_json(group, key, value) for key, value in values.items()})
        return cls(**top)

    def save(self, path: str | Path) -> None:
        """Write :meth:`to_dict` as JSON to ``path``."""
        text = json.dumps(self.to_dict(), indent=2, allow_nan=False)
        Path(path).write_text(text + "\n", encoding="utf-8")

    @classmethod
    def load(cls, path: str | Path) -> EnvConfig:
        """Read a config written by :meth:`save`."""
        return cls.from_dict(json.loads(Path(path).read_text(encoding="utf-8")))


_GROUPS.update(task=TaskConfig, timing=TimingConfig, force=ForceConfig, reward=RewardConfig, context=ContextConfig,
               render=RenderConfig)


def _to_json(value: Any) -> Any:
    if isinstance(value, (CupClearance, ForceProfileSettings)):
        return {f.name: getattr(value, f.name) for f in fields(value)}
    if isinstance(value, tuple):
        return [_to_json(item) for item in value]
    if isinstance(value, dict):
        return {key: _to_json(item) for key, item in value.items()}
    return value


def _from_json(group: str, key: str, value: Any) -> Any:
    kinds = {("task", "cup_clearance"): CupClearance, ("force", "force_learning"): ForceProfileSettings}
    kind = kinds.get((group, key))
    if kind is None or not isinstance(value, Mapping):
        return value
    names = {f.name for f in fields(kind)}
    if not set(value) <= names:
        raise ValueError(f"{key}: unknown entries {sorted(set(value) - names)} of a {kind.__name__}; expected some of "
                         f"{sorted(names)}")
    return kind(**value)
