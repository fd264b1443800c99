"""The affine map between the black-box action ``a in [-1, 1]^n`` and the joint-space DMP's parameters.

``theta = theta0 + scale * a`` over the selected groups in the DMP's own order (:mod:`rdmp_gym.dmp.parameters`), one
action dimension per parameter, so ``a = 0`` is the initial DMP. The weights', initial conditions' and amplitude's
scales are :class:`rdmp_gym.envs.action.ActionMap`'s rules; unlike the wiping task, the ``anchor`` (the posture the
rhythm is centred on) may be in the action here, scaled by a fraction of each joint's motion in the cycle.

``tempo`` is the wrapper's own group (not one of the DMP's parameters): one last action dimension, the speed factor
of the rollout (``tempo = 1 + scale * a``, default scale 0.5, so ``a = +1`` runs the cycle 1.5x faster and ``a = -1``
at half speed; the canonical system's frequency, transient and cycle alike).

``feedback`` (with the wrapper's setting ``feedback="linear"``) is the other wrapper group, always last: the gains
``K [n actions, m features]`` of the reacting term, row-major, ``K = scale * unit * a`` with ``K = 0`` at ``a = 0``
(``unit``: see :class:`JointParameterMap`).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

import numpy as np
from rdmp_gym.envs.action import ActionMap

from rdmp_gym import RhythmicDMP

from .defaults import BLACKBOX_SCALES

__all__ = ["FEEDBACK", "TEMPO", "JointParameterMap"]

#: the wrapper's speed group: one action dimension, ``tempo = 1 + scale * a``
TEMPO = "tempo"
#: the wrapper's group of feedback gains, last in the action
FEEDBACK = "feedback"


class JointParameterMap:
    """Affine action <-> parameter map of a joint-space DMP.

    Args:
        dmp: the initial DMP.
        groups: the parameter groups in the action (``periodic``, ``transient[:k]``, ``initial[:k]``, ``amplitude``,
            ``anchor``, and the wrapper's ``tempo``; not ``stop`` or ``sweep``).
        scales: ``{group: frac}`` over :data:`~rdmp_gym.envs.blackbox.defaults.BLACKBOX_SCALES`.
        motion: ``[d]`` each joint's peak-to-peak motion in the initial DMP's cycle (scales the anchor).
        feedback_units: ``[n, m]`` the unit of each feedback gain (action units per standard deviation), times the
            ``feedback`` scale its action scale; None: no feedback group.

    Attributes:
        dmp_groups: the selected groups of the DMP (``groups`` less ``tempo``).
        slices: ``{group: slice}`` of the action, ``tempo`` after the DMP's groups where selected, ``feedback`` last.
        theta0, scale: ``[P]`` the initial parameters and the action scales.
        feedback_shape: ``(n, m)`` of the feedback gains, None without them.
    """

    def __init__(self, dmp: RhythmicDMP, groups: Iterable[str] | str, scales: Mapping[str, float] | None,
                 motion: np.ndarray, feedback_units: np.ndarray | None = None) -> None:
        groups = (groups,) if isinstance(groups, str) else tuple(groups)
        if not groups:
            raise ValueError("groups: expected at least one parameter group")
        if groups.count(TEMPO) > 1:
            raise ValueError(f"groups: {TEMPO!r} is given {groups.count(TEMPO)} times, expected once")
        self.dmp_groups = tuple(group for group in groups if group != TEMPO)
        self.has_tempo = TEMPO in groups
        names = dmp.layout.resolve(self.dmp_groups) if self.dmp_groups else []
        if FEEDBACK in groups:
            raise ValueError(f"groups: {FEEDBACK!r} is not a group to select; the setting feedback='linear' adds it")
        bad = [name for name in names if name in ("stop", "sweep")]
        if bad:
            raise ValueError(f"groups: {bad} cannot be in the black-box action (no stop or sweep in joint space)")
        scales = dict(scales or {})
        for key, value in scales.items():
            if not (isinstance(value, (int, float, np.floating)) and np.isfinite(value) and value > 0):
                raise ValueError(f"scales: {key} must be a finite number > 0, got {value!r}")
        allowed = set(names) | {name.split(":")[0] for name in names} | ({TEMPO} if self.has_tempo else set()) \
            | ({FEEDBACK} if feedback_units is not None else set())
        unknown = set(scales) - allowed
        if unknown:
            raise ValueError(f"scales: {sorted(unknown)} are not among the selected groups {sorted(allowed)}")
        self.groups = groups
        self.slices = dmp.param_slices(self.dmp_groups) if self.dmp_groups else {}
        self.theta0 = dmp.get_params(self.dmp_groups).astype(np.float64) if self.dmp_groups else np.zeros(0)
        self.scale = np.zeros_like(self.theta0)
        merged = {**BLACKBOX_SCALES, **scales}
        others = tuple(name for name in self.slices if name != "anchor")
        if others:
            inner = ActionMap(dmp, others, {k: v for k, v in merged.items()
                                            if k in set(others) | {n.split(":")[0] for n in others}})
            for name in others:
                self.scale[self.slices[name]] = inner.scale[inner.slices[name]]
        if "anchor" in self.slices:
            motion = np.asarray(motion, dtype=np.float64)
            span = np.maximum(motion, max(0.25 * float(motion.max()), 1e-6))
            self.scale[self.slices["anchor"]] = float(merged["anchor"]) * span
        if self.has_tempo:
            if not float(merged[TEMPO]) < 1.0:
                raise ValueError(f"scales: tempo must be < 1 (a = -1 runs at speed 1 - scale), got {merged[TEMPO]!r}")
            self.slices = {**self.slices, TEMPO: slice(self.theta0.size, self.theta0.size + 1)}
            self.theta0 = np.append(self.theta0, 1.0)
            self.scale = np.append(self.scale, float(merged[TEMPO]))
        self._policy_size = int(self.theta0.size)
        self.feedback_shape = None if feedback_units is None else self._add_feedback(feedback_units,
                                                                                     float(merged[FEEDBACK]))
        self.size = int(self.theta0.size)

    def _add_feedback(self, units: np.ndarray, scale: float) -> tuple[int, int]:
        """Append the feedback group (``theta0 = 0``, scale ``scale * units``); its shape ``(n, m)``."""
        units = np.asarray(units, dtype=np.float64)
        if units.ndim != 2 or units.size == 0 or not np.all(np.isfinite(units)) or np.any(units <= 0.0):
            raise ValueError(f"feedback_units: expected [n, m] finite units > 0, got shape {units.shape}")
        start = self.theta0.size
        self.slices = {**self.slices, FEEDBACK: slice(start, start + units.size)}
        self.theta0 = np.append(self.theta0, np.zeros(units.size))
        self.scale = np.append(self.scale, scale * units.ravel())
        return int(units.shape[0]), int(units.shape[1])

    def feedback_gains(self, theta: np.ndarray) -> np.ndarray | None:
        """``K [n, m]`` of ``theta [P]`` (None without the feedback group)."""
        if self.feedback_shape is None:
            return None
        return np.asarray(theta, dtype=np.float64)[self.slices[FEEDBACK]].reshape(self.feedback_shape)

    def split(self, theta: np.ndarray) -> tuple[np.ndarray, float]:
        """``theta [P]`` taken apart: the DMP's parameters (``theta`` less ``tempo`` and ``feedback``) and the tempo
        (1.0 without ``tempo``)."""
        theta = np.asarray(theta, dtype=np.float64)
        if theta.shape != self.theta0.shape:
            raise ValueError(f"theta: expected shape {self.theta0.shape}, got {theta.shape}")
        theta = theta[:self._policy_size]
        if not self.has_tempo:
            return theta, 1.0
        return theta[:-1], float(theta[-1])

    def to_params(self, action: np.ndarray) -> np.ndarray:
        """``theta [P]`` (float64) of an action ``[P]``."""
        return self.theta0 + self.scale * np.asarray(action, dtype=np.float64)

    def to_action(self, theta: np.ndarray) -> np.ndarray:
        """The action ``[P]`` (float32, not clipped) of ``theta [P]``; ValueError for a wrong shape or NaN."""
        theta = np.asarray(theta, dtype=np.float64)
        if theta.shape != self.theta0.shape:
            raise ValueError(f"theta: expected shape {self.theta0.shape}, got {theta.shape}")
        if not np.all(np.isfinite(theta)):
            raise ValueError("theta: contains NaN or infinite values")
        return ((theta - self.theta0) / self.scale).astype(np.float32)
