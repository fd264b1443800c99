"""The ``approach`` action group: one action dimension that raises (or lowers) the approach as a whole.

With the smooth core (``alpha_z = 5``, wide overlapping basis functions, a fit that leaves the approach
to the spring and the smooth start) a transient weight moves the path by only ``scale / (alpha_z beta_z)``:
at the default scales, all transient height weights at +1 lift the approach by about 2 mm, while a cup
(8 cm tall) in the corridor needs 4-6 cm. Larger per-weight scales would give the lift, but make uniformly
random actions rough (independent weights at 28x the scale: jerk ratio up to 95, 19 rad/s²).
The default lift, 6 cm at ``a = +1`` (``scales={"approach": ...}``), clears the cup in the nominal context
and is the largest whole centimetre that keeps the peak joint acceleration under ARMAR-III's 10 rad/s²
there (7 cm: 11.7 rad/s²). ``a = -1`` lowers the approach by as much (it then hits the cup harder).

So the env offers a coordinated, low-dimensional direction in the DMP's own parameters: a fixed
combination ``delta`` of the transient's height weights whose rollout lifts the approach by a smooth
bump ``lift(t)`` (quintic rise, hold while the sponge passes the corridor, quintic fall before
touchdown), ``height`` metres at ``a = +1``. ``theta = theta_imitation + scale * a + a_approach * delta``
stays a DMP parameter vector: the path is still the DMP's own rollout, and a learner can move the
same weights one by one. ``delta`` is found once per env by least squares on the DMP's linear response
to each height weight (with a second-difference penalty, so that the weights themselves are smooth).
"""

from __future__ import annotations

import numpy as np

from rdmp_gym import RhythmicDMP

__all__ = ["LIFT_PROFILE", "approach_direction", "lift_profile"]

#: The bump as fractions of the transient's length: rise over [0, 0.35], hold to 0.6, fall to 0 at 0.88.
#: The imitation passes the corridor's cup at 0.36-0.71 of the transient and touches down at 0.87. This
#: gentle bump lifts 6 cm with a jerk ratio of 2.0 and 5.8 rad/s² peak joint acceleration (nominal
#: context); a steeper one, (0.25, 0.62, 0.85), cleared no more cups with 4.4 and 8.2 rad/s².
LIFT_PROFILE = (0.35, 0.6, 0.88)


def _quintic(x: np.ndarray) -> np.ndarray:
    """Minimum-jerk step 0 -> 1 on [0, 1] (zero slope and curvature at both ends), clipped outside."""
    x = np.clip(x, 0.0, 1.0)
    return x**3 * (10.0 - 15.0 * x + 6.0 * x**2)


def lift_profile(times: np.ndarray, length: float, profile: tuple[float, float, float] = LIFT_PROFILE
                 ) -> np.ndarray:
    """The target lift ``[T]`` in [0, 1] at ``times [T]`` for a transient of ``length`` s."""
    rise, hold, fall = (f * length for f in profile)
    t = np.asarray(times, dtype=np.float64)
    return _quintic(t / rise) * (1.0 - _quintic((t - hold) / (fall - hold)))


def approach_direction(dmp: RhythmicDMP, groups: tuple[str, ...], times: np.ndarray, height: float,
                       smoothness: float = 1e-3) -> np.ndarray:
    """The direction ``delta [P]`` in the parameters of ``groups`` that lifts the approach by ``height *
    lift_profile(times)`` (m): only the height (last dimension) weights of transient 0 move.

    Args:
        dmp: the imitation DMP; ``groups`` must select ``transient:0`` (``"transient"`` does).
        times: ``[T]`` control times from the start (the response to the weights is linear and does not
            depend on the start or the anchor, so the demonstrated ones are used).
        height: lift (m) at the top of the bump.
        smoothness: weight of the weights' second differences relative to the fit.
    """
    slices = dmp.param_slices(groups)
    if "transient:0" not in slices:
        raise ValueError("groups: the approach group needs the transient weights (group 'transient') in the action")
    part = slices["transient:0"]
    d = dmp.n_dims
    count = (part.stop - part.start) // d
    rows = part.start + (d - 1) * count + np.arange(count)              # height weights of transient 0
    theta0 = dmp.get_params(groups).astype(np.float64)
    thetas = np.tile(theta0, (count + 1, 1))
    thetas[np.arange(1, count + 1), rows] += 1.0
    paths = dmp.rollout_batch(thetas, times, groups=groups, start_blend=True)
    response = (paths[1:, :, -1] - paths[0, :, -1]).T                   # [T, M]: lift per unit weight
    target = height * lift_profile(times, dmp.transients[0].length)
    second = np.diff(np.eye(count), 2, axis=0)
    scale = float(np.sum(response**2)) / count
    lhs = response.T @ response + smoothness * scale * (second.T @ second) + 1e-9 * scale * np.eye(count)
    weights = np.linalg.solve(lhs, response.T @ target)
    delta = np.zeros_like(theta0)
    delta[rows] = weights
    return delta
