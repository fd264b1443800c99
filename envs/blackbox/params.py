"""The affine map between the black-box action ``a in [-1, 1]^n`` and the joint-space DMP's parameters.

``theta = theta0 + scale * a`` over the selected groups in the DMP's own order (:mod:`rdmp_gym.parameters`), one
action dimension per parameter, so ``a = 0`` is the initial DMP. The weights', initial conditions' and amplitude's
scales are :class:`rdmp_gym.envs.action.ActionMap`'s rules; unlike the wiping task, the ``anchor`` (the posture the
rhythm is centred on) may be in the action here, scaled by a fraction of each joint's motion in the cycle.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

import numpy as np
from rdmp_gym.envs.action import ActionMap

from rdmp_gym import RhythmicDMP

from .defaults import BLACKBOX_SCALES

__all__ = ["JointParameterMap"]


class JointParameterMap:
    """Affine action <-> parameter map of a joint-space DMP.

    Args:
        dmp: the initial DMP.
        groups: the parameter groups in the action (``periodic``, ``transient[:k]``, ``initial[:k]``, ``amplitude``,
            ``anchor``; not ``stop`` or ``sweep``).
        scales: ``{group: frac}`` over :data:`~rdmp_gym.envs.blackbox.defaults.BLACKBOX_SCALES`.
        motion: ``[d]`` each joint's peak-to-peak motion in the initial DMP's cycle (scales the anchor).
    """

    def __init__(self, dmp: RhythmicDMP, groups: Iterable[str] | str, scales: Mapping[str, float] | None,
                 motion: np.ndarray) -> None:
        groups = (groups,) if isinstance(groups, str) else tuple(groups)
        if not groups:
            raise ValueError("groups: expected at least one parameter group")
        names = dmp.layout.resolve(groups)
        bad = [name for name in names if name in ("stop", "sweep")]
        if bad:
            raise ValueError(f"groups: {bad} cannot be in the black-box action (no stop or sweep in joint space)")
        scales = dict(scales or {})
        for key, value in scales.items():
            if not (isinstance(value, (int, float, np.floating)) and np.isfinite(value) and value > 0):
                raise ValueError(f"scales: {key} must be a finite number > 0, got {value!r}")
        allowed = set(names) | {name.split(":")[0] for name in names}
        unknown = set(scales) - allowed
        if unknown:
            raise ValueError(f"scales: {sorted(unknown)} are not among the selected groups {sorted(allowed)}")
        self.groups = groups
        self.slices = dmp.param_slices(groups)
        self.theta0 = dmp.get_params(groups).astype(np.float64)
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
        self.size = int(self.theta0.size)

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
