"""The affine map between the env's action ``a in [-1, 1]^n`` and the DMP parameter vector.

``theta = theta_imitation + scale * a``, so ``a = 0`` is the imitation fit. Per-group scales:

- ``periodic`` / ``transient:k`` weights: ``frac`` x the per-dimension range (max - min) of the
  imitation weights of that group, floored at a quarter of the largest dimension's range (so a
  dimension that is flat in the demonstration, such as the height while wiping, can still be moved);
- ``initial:k`` = ``(phi0, r0)``: ``frac * pi`` for the phase and ``frac * r0`` for the radius, so
  with ``frac < 1`` every action keeps ``r0 > 0``. With a larger ``frac``, an action that makes
  ``r0 <= 0`` is an invalid parameter vector (penalised, not simulated);
- ``amplitude`` (``[d]`` factors about the anchor, 1 in the imitation): ``frac`` itself, so the
  movement can grow or shrink by up to ``frac`` in each dimension (to fit a larger or smaller patch);
- extra ``directions`` (the env's ``approach``, :mod:`rdmp_gym.envs.approach`): one action dimension each,
  appended after the parameters, that moves theta along a fixed direction given per unit of its scale
  (``approach``: metres of lift at ``a = +1``). ``to_action`` puts 0 there (every theta is reachable
  through the parameters themselves).

The ``anchor`` group cannot be in the action: the anchor is the dirt patch centre from the context.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

import numpy as np

from rdmp_gym import RhythmicDMP

__all__ = ["DEFAULT_SCALES", "ActionMap"]

#: Default fractions. Chosen so that a uniformly random action stays a plausible wiping motion: with
#: them the path deviates 1.6-3 cm from the imitation and joint speeds stay below 2 rad/s (style 1,
#: 16 random actions), while coordinated actions still change the pattern's amplitude by ~20 %.
#: ``approach``: 6 cm of lift at +1, which clears the corridor's 8 cm cup in the nominal context within
#: ARMAR-III's joint acceleration limit (see :mod:`rdmp_gym.envs.approach`).
DEFAULT_SCALES = {"periodic": 0.1, "transient": 0.1, "initial": 0.1, "amplitude": 0.5, "approach": 0.06}


class ActionMap:
    """Affine action <-> parameter map for one DMP and one group selection.

    Args:
        dmp: the imitation DMP.
        groups: parameter groups in the action (``periodic``, ``transient[:k]``, ``initial[:k]``, ``amplitude``).
        scales: ``{group: frac}`` overrides of :data:`DEFAULT_SCALES` (short or full group names).
        directions: ``{name: delta [P]}`` extra action dimensions (theta moves by ``scale * a * delta``).
    """

    def __init__(self, dmp: RhythmicDMP, groups: Iterable[str] | str, scales: Mapping[str, float] | None = None,
                 directions: Mapping[str, np.ndarray] | None = None):
        groups = (groups,) if isinstance(groups, str) else tuple(groups)
        names = dmp.layout.resolve(groups)
        if "anchor" in names:
            raise ValueError("groups: 'anchor' cannot be in the action; the anchor is the patch centre "
                             "given by the context")
        scales = dict(scales or {})
        directions = dict(directions or {})
        allowed = set(names) | {n.split(":")[0] for n in names} | set(directions)
        unknown = set(scales) - allowed
        if unknown:
            raise ValueError(f"scales: {sorted(unknown)} are not among the selected groups {sorted(allowed)}")
        for key, value in scales.items():
            if not (isinstance(value, (int, float, np.floating)) and np.isfinite(value) and value > 0):
                raise ValueError(f"scales: {key} must be a finite number > 0, got {value!r}")
        self.groups = groups
        self.slices = dmp.param_slices(groups)
        self.theta0 = dmp.get_params(groups).astype(np.float64)
        self.scale = np.zeros_like(self.theta0)
        self.r0_index: list[int] = []
        d = dmp.n_dims
        for name, part in self.slices.items():
            short = name.split(":")[0]
            frac = float(scales.get(name, scales.get(short, DEFAULT_SCALES[short])))
            if short == "initial":
                self.scale[part] = [frac * np.pi, frac * self.theta0[part.start + 1]]
                self.r0_index.append(part.start + 1)
            elif short == "amplitude":
                self.scale[part] = frac
            else:
                w = self.theta0[part].reshape(d, -1)
                spread = w.max(axis=1) - w.min(axis=1)
                spread = np.maximum(spread, max(0.25 * spread.max(), 1e-3))
                self.scale[part] = np.repeat(frac * spread, w.shape[1])
        #: ``[n_directions, P]``: each extra action dimension's step in theta at ``a = +1``
        self.directions = np.array([float(scales.get(name, DEFAULT_SCALES.get(name, 1.0)))
                                    * np.asarray(delta, dtype=np.float64) for name, delta in directions.items()]
                                   ).reshape(len(directions), self.theta0.size)
        self.direction_names = tuple(directions)
        self.size = self.theta0.size + len(directions)

    def to_params(self, action: np.ndarray) -> np.ndarray:
        """``theta [P]`` (float64) of an action ``[P + n_directions]``."""
        action = np.asarray(action, dtype=np.float64)
        count = self.theta0.size
        return self.theta0 + self.scale * action[:count] + action[count:] @ self.directions

    def to_action(self, theta: np.ndarray) -> np.ndarray:
        """An action ``[P + n_directions]`` (float32, not clipped) that gives ``theta [P]`` (0 in the directions)."""
        theta = np.asarray(theta, dtype=np.float64)
        if theta.shape != self.theta0.shape:
            raise ValueError(f"theta: expected shape {self.theta0.shape}, got {theta.shape}")
        if not np.all(np.isfinite(theta)):
            raise ValueError("theta: contains NaN or infinite values")
        return np.r_[(theta - self.theta0) / self.scale, np.zeros(len(self.directions))].astype(np.float32)

    def r0_violation(self, theta: np.ndarray) -> float:
        """How far the radii ``r0`` of ``theta`` are from positive, relative to the imitation ones (0 if valid)."""
        worst = 0.0
        for index in self.r0_index:
            if theta[index] <= 0.0:
                worst = max(worst, (self.theta0[index] - theta[index]) / self.theta0[index])
        return worst
