"""The settings of the rhythmic black-box wrapper: one typed, validated, frozen record.

:class:`BlackBoxSettings` holds everything :class:`~rdmp_gym.envs.blackbox.RhythmicBlackBoxWrapper` is built with
but the env itself. Every setting is checked here, where it does not need the env (a number is finite and in range,
a name is one the wrapper knows, a callable is callable); what needs the env (one gain per joint, a context mask as
long as the observation) is checked when the wrapper is built. A setting left ``None`` is filled in by the wrapper:
from :data:`~rdmp_gym.envs.blackbox.defaults.ENV_DEFAULTS` for a known env, else from the MuJoCo model
(:func:`~rdmp_gym.envs.blackbox.defaults.model_defaults`), else from the generic fallback named with the field.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rdmp_gym import Demonstration, RhythmicDMP

from .controller import CONTROLLERS, JointReader, TrackingController
from .defaults import check_start

__all__ = ["DEFAULT_GROUPS", "FEEDBACKS", "BlackBoxSettings"]

#: the parameter groups in the action by default: the cycle's shape, its amplitude and the posture it is centred on
DEFAULT_GROUPS = ("periodic", "amplitude", "anchor")

#: the reacting policies the setting ``feedback`` names (None: the open-loop DMP alone)
FEEDBACKS = ("linear",)

Numbers = float | tuple[float, ...]


def _positive(value: Any, name: str, allow_zero: bool = False) -> float:
    """``value`` as a finite float > 0 (>= 0 with ``allow_zero``); ValueError naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"{name}: expected a number, got {value!r}")
    number = float(value)
    if not np.isfinite(number) or number < 0.0 or (number == 0.0 and not allow_zero):
        raise ValueError(f"{name}: expected a finite number {'>=' if allow_zero else '>'} 0, got {value!r}")
    return number


def _numbers(value: Any, name: str, what: str, check: Any = None) -> Numbers | None:
    """None, a number or a flat sequence of numbers (a tuple), each finite and passing ``check``; ValueError naming
    ``name`` and saying ``what`` was expected."""
    if value is None:
        return None
    if isinstance(value, bool):
        raise ValueError(f"{name}: expected {what}, got {value!r}")
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise ValueError(f"{name}: expected {what}, got {value!r}") from error
    if array.ndim > 1 or array.size == 0 or not np.all(np.isfinite(array)) \
            or (check is not None and not np.all(check(array))):
        raise ValueError(f"{name}: expected {what}, got {value!r}")
    return float(array) if array.ndim == 0 else tuple(float(x) for x in array)


def _count(value: Any, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or int(value) < 1:
        raise ValueError(f"{name}: expected a whole number >= 1 of basis functions, got {value!r}")
    return int(value)


@dataclass(frozen=True, eq=False)
class BlackBoxSettings:
    """The rhythmic black-box wrapper's settings (all but the env). ``None``: filled in when the wrapper is built.

    Attributes:
        groups: the DMP parameter groups in the action (:data:`DEFAULT_GROUPS`; also ``transient``, ``initial``, and
            ``tempo``: the cycle's speed as one more action dimension, ``tempo = 1 + 0.5 a``).
        duration: the episode (s), a whole number of env steps within the env's time limits; None: the env's time
            limit (its ``spec.max_episode_steps`` or a ``TimeLimit`` wrapper); an env with neither needs it.
        controller: ``"pd"`` (joint torques), ``"position"`` or ``"velocity"`` (joint targets), or a callable
            ``(q_des, qd_des, q, qd) -> action``; None: from the MuJoCo model's actuators (motors: ``"pd"``,
            position servos: ``"position"``, velocity servos: ``"velocity"``), else ``"pd"``.
        p_gains, d_gains: the built-in controllers' gains, a number or one per joint, in action units per joint unit
            (and per joint unit/s); None: derived from the MuJoCo model (``"pd"`` on motors), else ``"pd"`` needs
            ``p_gains`` (``d_gains`` then: critical damping on a MuJoCo model, else 0).
        context_mask: booleans selecting the context from the flattened reset observation; None: all of it.
        demonstration: a joint-space :class:`~rdmp_gym.Demonstration` ``Y [L, d]`` to fit the initial DMP to.
        dmp: a fitted :class:`~rdmp_gym.RhythmicDMP` with ``d`` dimensions to start from (not with
            ``demonstration``).
        n_periodic, n_transient: basis functions of the fitted DMP.
        period: the default pattern's period (s); None: the model's natural period, else 1 s.
        amplitude: the default pattern's amplitude (joint units, a number or one per joint, > 0); None: from the
            joints' ranges, else 0.2.
        phases: per joint phases (rad), or a number: the lag between neighbouring joints; None: pi/2.
        start_periods: the default pattern's start from rest (its growth from the posture into the rhythm, which
            the DMP's transient learns), in periods, at least 0.05; None: 1.
        posture: ``[d]`` the default pattern's anchor; None: the MuJoCo env's ``init_qpos`` at the joints (inside
            their ranges), else the joint positions after ``env.reset(seed=0)``.
        joint_state: ``reader(env) -> (q [d], qd [d])``; None: the joints of a MuJoCo model's actuators.
        dt: seconds per env step; None: ``env.unwrapped.dt``.
        scales: ``{group: frac}`` action scales over :data:`~rdmp_gym.envs.blackbox.defaults.BLACKBOX_SCALES`.
        fit_kwargs: settings of :meth:`RhythmicDMP.fit <rdmp_gym.RhythmicDMP.fit>` (``period``, ``alpha_z``, ...).
        feedback: None (the open-loop DMP: the policy never sees the body) or ``"linear"``: the controller's command
            gains ``K z``, ``K [n actions, m observation features]`` the last group of the action (``feedback``, zero
            at ``a = 0``), ``z [m]`` the env's flattened observation standardised on the ``a = 0`` gait
            (:class:`~rdmp_gym.envs.blackbox.controller.LinearFeedback`).
    """

    groups: tuple[str, ...] = DEFAULT_GROUPS
    duration: float | None = None
    controller: str | TrackingController | None = None
    p_gains: Numbers | None = None
    d_gains: Numbers | None = None
    context_mask: tuple[bool, ...] | None = None
    demonstration: Demonstration | None = None
    dmp: RhythmicDMP | None = None
    n_periodic: int = 10
    n_transient: int = 10
    period: float | None = None
    amplitude: Numbers | None = None
    phases: Numbers | None = None
    start_periods: float | None = None
    posture: tuple[float, ...] | None = None
    joint_state: JointReader | None = None
    dt: float | None = None
    scales: Mapping[str, float] = field(default_factory=dict)
    fit_kwargs: Mapping[str, Any] = field(default_factory=dict)
    feedback: str | None = None

    def __post_init__(self) -> None:
        put = object.__setattr__
        put(self, "groups", self._groups(self.groups))
        if self.duration is not None:
            put(self, "duration", _positive(self.duration, "duration"))
        if self.controller is not None and not callable(self.controller) and self.controller not in CONTROLLERS:
            raise ValueError(f"controller: expected one of {CONTROLLERS} or a callable (q_des, qd_des, q, qd) -> "
                             f"action, got {self.controller!r}")
        gains = "a number or one number per joint, each finite and >= 0"
        put(self, "p_gains", _numbers(self.p_gains, "p_gains", gains, lambda x: x >= 0))
        put(self, "d_gains", _numbers(self.d_gains, "d_gains", gains, lambda x: x >= 0))
        put(self, "context_mask", self._mask(self.context_mask))
        if self.demonstration is not None and not isinstance(self.demonstration, Demonstration):
            raise ValueError(f"demonstration: expected a rdmp_gym.Demonstration, got "
                             f"{type(self.demonstration).__name__}")
        if self.dmp is not None:
            if not isinstance(self.dmp, RhythmicDMP):
                raise ValueError(f"dmp: expected a RhythmicDMP, got {type(self.dmp).__name__}")
            if self.demonstration is not None:
                raise ValueError("dmp: give a fitted dmp or a demonstration, not both")
        put(self, "n_periodic", _count(self.n_periodic, "n_periodic"))
        put(self, "n_transient", _count(self.n_transient, "n_transient"))
        if self.period is not None:
            put(self, "period", _positive(self.period, "period"))
        put(self, "amplitude", _numbers(self.amplitude, "amplitude", "a number or one number per joint, each > 0 "
                                        "(joint units)", lambda x: x > 0))
        put(self, "phases", _numbers(self.phases, "phases", "a number (the lag between neighbouring joints, rad) or "
                                     "one finite phase per joint"))
        if self.start_periods is not None:
            put(self, "start_periods", check_start(self.start_periods, "start_periods"))
        posture = _numbers(self.posture, "posture", "[d] finite joint positions")
        put(self, "posture", None if posture is None else tuple(np.atleast_1d(posture).tolist()))
        if self.joint_state is not None and not callable(self.joint_state):
            raise ValueError(f"joint_state: expected a callable env -> (q [d], qd [d]), got "
                             f"{type(self.joint_state).__name__}")
        if self.dt is not None:
            put(self, "dt", _positive(self.dt, "dt"))
        put(self, "scales", self._mapping(self.scales, "scales"))
        put(self, "fit_kwargs", self._mapping(self.fit_kwargs, "fit_kwargs"))
        if self.feedback is not None and (not isinstance(self.feedback, str) or self.feedback not in FEEDBACKS):
            raise ValueError(f"feedback: expected None (open loop) or one of {FEEDBACKS}, got {self.feedback!r}")

    @staticmethod
    def _groups(groups: Any) -> tuple[str, ...]:
        values = (groups,) if isinstance(groups, str) else groups
        if not isinstance(values, Iterable) or isinstance(values, Mapping):
            raise ValueError(f"groups: expected parameter group names, got {groups!r}")
        values = tuple(values)
        if not values or not all(isinstance(name, str) for name in values):
            raise ValueError(f"groups: expected at least one parameter group name, got {groups!r}")
        return values

    @staticmethod
    def _mask(mask: Any) -> tuple[bool, ...] | None:
        if mask is None:
            return None
        values = np.asarray(mask)
        if values.dtype != bool or values.ndim != 1:
            raise ValueError(f"context_mask: expected booleans (one per entry of the env's flattened observation), "
                             f"got {values.dtype} array of shape {values.shape}")
        return tuple(bool(x) for x in values)

    @staticmethod
    def _mapping(value: Any, name: str) -> dict[str, Any]:
        if value is None:
            return {}
        if not isinstance(value, Mapping) or not all(isinstance(key, str) for key in value):
            raise ValueError(f"{name}: expected a mapping of names to values, got {value!r}")
        return dict(value)

    @classmethod
    def names(cls) -> tuple[str, ...]:
        """The settings' names, in order."""
        return tuple(item.name for item in dataclasses.fields(cls))

    @classmethod
    def build(cls, settings: BlackBoxSettings | None = None, **overrides: Any) -> BlackBoxSettings:
        """``settings`` (default: all defaults) with ``overrides`` replacing its fields, validated.

        Raises:
            TypeError: ``settings`` is not a :class:`BlackBoxSettings`, or an override is no setting (naming it).
            ValueError: a setting's value is refused (naming it).
        """
        if settings is None:
            settings = cls()
        elif not isinstance(settings, cls):
            raise TypeError(f"settings: expected a BlackBoxSettings, got {type(settings).__name__}")
        unknown = sorted(set(overrides) - set(cls.names()))
        if unknown:
            raise TypeError(f"{unknown[0]}: not a setting of the rhythmic black-box wrapper "
                            f"(its settings: {', '.join(cls.names())})")
        return dataclasses.replace(settings, **overrides) if overrides else settings
