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
- extra ``directions`` (the env's ``approach``, :mod:`rdmp_gym.envs.tasks.wiping.approach`, and ``sweep_x``/``sweep_y``,
  :mod:`rdmp_gym.envs.tasks.wiping.coverage`): one action dimension each, appended after the parameters, that moves
  theta along a fixed direction given per unit of its scale (``approach``: metres of lift at ``a = +1``);
- ``driven`` groups (the env's ``sweep``): in theta, but without action dimensions of their own; only the
  directions move them. ``to_action`` finds the directions' values from a theta's driven part by least
  squares and puts 0 in the other directions (every other theta is reachable through the parameters).

The ``anchor`` group cannot be in the action: the anchor is the dirt patch centre from the context.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

from rdmp_gym import RhythmicDMP

__all__ = ["DEFAULT_SCALES", "ActionMap", "checked_action"]

#: Default fractions. Chosen so that a uniformly random action stays a plausible wiping motion: with
#: them the path deviates 1.6-3 cm from the imitation and joint speeds stay below 2 rad/s (style 1,
#: 16 random actions), while coordinated actions still change the pattern's amplitude by ~20 %.
#: ``approach``: 6 cm of lift at +1, which clears the corridor's 8 cm cup in the nominal context within
#: ARMAR-III's joint acceleration limit (see :mod:`rdmp_gym.envs.tasks.wiping.approach`). ``sweep_x``/``sweep_y``: the
#: covering rectangle's half-extent at +1 (m; :mod:`rdmp_gym.envs.tasks.wiping.coverage`): with the loop (5 cm radius)
#: and the pad, 6 cm reaches well past the largest drawn patch (22 cm a side).
DEFAULT_SCALES = {"periodic": 0.1, "transient": 0.1, "initial": 0.1, "amplitude": 0.5, "approach": 0.06,
                  "sweep_x": 0.06, "sweep_y": 0.06}


def checked_action(action: Any, shape: tuple[int, ...]) -> np.ndarray:
    """``action`` as float64 of ``shape`` (not clipped); ValueError naming ``action`` for a non-numeric value, a
    wrong shape, NaN or infinite values."""
    try:
        a = np.asarray(action, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise ValueError(f"action: expected a numeric array of shape {shape}") from error
    if a.shape != shape:
        raise ValueError(f"action: expected shape {shape}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError("action: contains NaN or infinite values")
    return a


class ActionMap:
    """Affine action <-> parameter map for one DMP and one group selection.

    Args:
        dmp: the imitation DMP.
        groups: parameter groups in the action (``periodic``, ``transient[:k]``, ``initial[:k]``, ``amplitude``).
        scales: ``{group: frac}`` overrides of :data:`DEFAULT_SCALES` (short or full group names).
        directions: ``{name: delta [P]}`` extra action dimensions (theta moves by ``scale * a * delta``).
        driven: groups among ``groups`` that have no action dimensions of their own (only directions move them).
    """

    def __init__(self, dmp: RhythmicDMP, groups: Iterable[str] | str, scales: Mapping[str, float] | None = None,
                 directions: Mapping[str, np.ndarray] | None = None, driven: Iterable[str] = ()):
        groups = (groups,) if isinstance(groups, str) else tuple(groups)
        names = dmp.layout.resolve(groups)
        driven = tuple(driven)
        if not set(driven) <= set(groups):
            raise ValueError(f"driven: {sorted(set(driven) - set(groups))} are not among the groups {groups}")
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
            frac = float(scales.get(name, scales.get(short, DEFAULT_SCALES.get(short, 1.0))))
            if short == "initial":
                self.scale[part] = [frac * np.pi, frac * self.theta0[part.start + 1]]
                self.r0_index.append(part.start + 1)
            elif short == "amplitude":
                self.scale[part] = frac
            elif short in driven:
                continue
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
        #: ``[P]``: whether a parameter has an action dimension of its own (False in the driven groups)
        self.free = np.ones(self.theta0.size, dtype=bool)
        for name in driven:
            self.free[self.slices[name]] = False
        self.n_free = int(self.free.sum())
        self.size = self.n_free + len(directions)

    def action_slices(self) -> dict[str, slice]:
        """``{name: slice of the action}``: each free group's own dimensions, then each direction's one."""
        slices, start = {}, 0
        for name, part in self.slices.items():
            if self.free[part].all():
                slices[name] = slice(start, start + part.stop - part.start)
                start += part.stop - part.start
        for name in self.direction_names:
            slices[name] = slice(start, start + 1)
            start += 1
        return slices

    def to_params(self, action: np.ndarray) -> np.ndarray:
        """``theta [P]`` (float64) of an action ``[n_free + n_directions]``."""
        action = np.asarray(action, dtype=np.float64)
        theta = self.theta0 + action[self.n_free:] @ self.directions
        theta[self.free] += self.scale[self.free] * action[:self.n_free]
        return theta

    def to_action(self, theta: np.ndarray) -> np.ndarray:
        """An action ``[n_free + n_directions]`` (float32, not clipped) that gives ``theta [P]``: the directions
        that move the driven groups by least squares, 0 in the others. ValueError if the driven part of
        ``theta`` is not reachable by those directions."""
        theta = np.asarray(theta, dtype=np.float64)
        if theta.shape != self.theta0.shape:
            raise ValueError(f"theta: expected shape {self.theta0.shape}, got {theta.shape}")
        if not np.all(np.isfinite(theta)):
            raise ValueError("theta: contains NaN or infinite values")
        along = np.zeros(len(self.directions))
        driven = ~self.free
        if driven.any():
            change = theta[driven] - self.theta0[driven]
            basis = self.directions[:, driven]
            moving = np.flatnonzero(np.any(basis != 0.0, axis=1))
            along[moving] = np.linalg.lstsq(basis[moving].T, change, rcond=None)[0]
            if not np.allclose(along @ basis, change, atol=1e-9 * (1.0 + np.abs(change).max())):
                raise ValueError("theta: its driven groups (e.g. the sweep's via points) are not reachable by the "
                                 f"action's directions {self.direction_names}")
        change = theta[self.free] - self.theta0[self.free] - along @ self.directions[:, self.free]
        free = change / self.scale[self.free]
        return np.r_[free, along].astype(np.float32)

    def r0_violation(self, theta: np.ndarray) -> float:
        """How far the radii ``r0`` of ``theta`` are from positive, relative to the imitation ones (0 if valid)."""
        worst = 0.0
        for index in self.r0_index:
            if theta[index] <= 0.0:
                worst = max(worst, (self.theta0[index] - theta[index]) / self.theta0[index])
        return worst
