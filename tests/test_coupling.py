"""Obstacle avoidance coupling (rdmp_gym.coupling): properties of the steering term and a core-only wiping scenario."""

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from rdmp_gym import RhythmicDMP, wiping_demonstration
from rdmp_gym.coupling import ObstacleAvoidance, avoiding_rollout

vectors = st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3).map(np.array)


@settings(max_examples=200, deadline=None, database=None, derandomize=True)
@given(vectors, vectors, vectors)
def test_steering_turns_away_without_doing_work(y, v, obstacle):
    term = ObstacleAvoidance(obstacle, gamma=50.0, beta=3.0)
    p = term.acceleration(y, v)
    assert np.all(np.isfinite(p))
    assert abs(p @ v) <= 1e-9 * (1.0 + np.linalg.norm(p) * np.linalg.norm(v))     # perpendicular to v
    assert p @ (obstacle - y) <= 1e-9 * (1.0 + np.linalg.norm(p))                  # away from the obstacle
    assert np.linalg.norm(p) <= 50.0 * np.linalg.norm(v) / (3.0 * np.e) + 1e-9       # gamma |v| max theta e^-b theta


@settings(max_examples=100, deadline=None, database=None, derandomize=True)
@given(vectors, vectors, vectors, st.integers(0, 2**31 - 1), vectors)
def test_steering_is_equivariant_under_rigid_motions(y, v, obstacle, seed, shift):
    # away from the singular states (on the obstacle, heading exactly at it), where round-off decides
    offset = obstacle - y
    assume(np.linalg.norm(offset) > 1e-3 and np.linalg.norm(np.cross(offset, v)) > 1e-6)
    rotation = Rotation.random(random_state=seed).as_matrix()
    p = ObstacleAvoidance(obstacle, distance_scale=0.3).acceleration(y, v)
    moved = ObstacleAvoidance(rotation @ obstacle + shift, distance_scale=0.3).acceleration(
        rotation @ y + shift, rotation @ v)
    np.testing.assert_allclose(moved, rotation @ p, atol=1e-7 * (1.0 + np.linalg.norm(p)))


def test_degenerate_states_and_distance_window():
    term = ObstacleAvoidance([1.0, 0.0], distance_scale=0.5)
    assert not np.any(term.acceleration([0.0, 0.0], [0.0, 0.0]))         # at rest
    assert not np.any(term.acceleration([0.0, 0.0], [1.0, 0.0]))         # heading straight at it (theta = 0)
    assert not np.any(term.acceleration([1.0, 0.0], [1.0, 0.0]))         # on the obstacle
    near = term.acceleration([0.0, 0.0], [1.0, 0.3])
    far = term.acceleration([-2.0, 0.0], [1.0, 0.3])                       # same angle, farther away
    assert near[1] > 0.0 and np.linalg.norm(far) < 1e-3 * np.linalg.norm(near)
    # in a subset of the DMP's dimensions
    partial = ObstacleAvoidance([1.0, 0.0], dims=(0, 2)).acceleration([0.0, 5.0, 0.0], [1.0, 9.0, 0.3])
    assert partial[1] == 0.0 and partial[2] > 0.0
    for bad in ([1.0], [np.nan, 0.0]):
        with pytest.raises(ValueError, match="obstacle"):
            ObstacleAvoidance(bad)
    with pytest.raises(ValueError, match="dims"):
        ObstacleAvoidance([1.0, 0.0], dims=(0, 0))


@pytest.fixture(scope="module")
def wiping():
    demo = wiping_demonstration(1, rng=0)
    return RhythmicDMP.fit(demo, n_periodic=30, periodic_overlap=0.9, smoothing=0.3, regularization=1e-4)


def test_wiping_circle_steers_around_an_obstacle_on_its_path(wiping):
    t = np.arange(0.0, 8.0, 2e-3)
    obstacle = np.array([0.05, 0.0, 0.0])                                 # on the wiped circle
    free = wiping.rollout(t)
    term = ObstacleAvoidance(obstacle, gamma=2e4, distance_scale=0.03)     # gains for the default alpha_z = 5
    y, yd = avoiding_rollout(wiping, t, term)
    periodic = t > 3.0
    free_distance = np.linalg.norm(free - obstacle, axis=1)
    assert free_distance[periodic].min() < 1e-3
    assert np.linalg.norm(y - obstacle, axis=1)[periodic].min() > 0.012
    # the pattern is back on the opposite side of the circle (the soft spring rejoins within about 0.4 s)
    far = free_distance > 0.09
    assert np.abs(y[far] - free[far]).max() < 2e-3
    assert np.abs(np.gradient(yd, 2e-3, axis=0)).max() < 4.0             # m/s^2, bounded (free path 1.1)

    def squared_jerk(velocity):
        return np.sum(np.gradient(np.gradient(velocity, 2e-3, axis=0), 2e-3, axis=0)[periodic] ** 2)

    _, free_velocity = wiping.rollout(t, return_velocity=True)
    assert squared_jerk(yd) < 8.0 * squared_jerk(free_velocity)
    # a low-passed coupling term (beyond Hoffmann et al.) keeps clear with less jerk still
    smooth, smooth_velocity = avoiding_rollout(wiping, t, ObstacleAvoidance(obstacle, gamma=2e4, distance_scale=0.03),
                                               smoothing=0.1)
    assert np.linalg.norm(smooth - obstacle, axis=1)[periodic].min() > 0.012
    assert squared_jerk(smooth_velocity) < 0.6 * squared_jerk(yd)
    # the stepper applies an object with an acceleration method like the explicit coupling vector
    a, b = wiping.start(2e-3), wiping.start(2e-3)
    for _ in range(1600):
        state = a.step(term)
    for _ in range(1600):
        c = term.acceleration(*b.state) / b.omega**2
        other = b.step(c)
    np.testing.assert_array_equal(state[0], other[0])


def test_env_baseline_keeps_clear_of_the_obstacle_and_still_wipes():
    gym = pytest.importorskip("gymnasium")
    from rdmp_gym.envs import ENV_ID
    from rdmp_gym.envs.obstacle_baseline import run_avoiding

    env = gym.make(ENV_ID, n_periods=3.0)
    options = {"table_height": 0.0, "table_tilt": [0.0, 0.0], "patch_centre": [0.0, 0.0], "patch_size": [0.12, 0.12],
               "sponge_start": [-0.07, 0.10, 0.08], "obstacle": 0}
    env.reset(seed=0, options=options)
    inner = env.unwrapped
    free = inner.rollout_path(inner.action_map.theta0)
    obstacle = np.array([0.05, 0.0])                                      # on the wiped circle
    assert np.linalg.norm(free[:, :2] - obstacle, axis=1).min() < 1e-3
    _, info = run_avoiding(env, obstacle)
    assert info["valid"] and not info["unstable"]
    assert info["obstacle_clearance"] > 8e-3
    assert info["coverage"] >= 0.9
    with pytest.raises(ValueError, match="obstacle_xy"):
        run_avoiding(env, [0.0, np.nan])


def test_env_baseline_reads_the_cup_from_the_context():
    gym = pytest.importorskip("gymnasium")
    from rdmp_gym.envs import ENV_ID
    from rdmp_gym.envs.obstacle_baseline import avoiding_path, cup_position

    env = gym.make(ENV_ID, n_periods=2.0)
    inner = env.unwrapped
    observation, _ = env.reset(seed=0, options={"obstacle": 0})
    assert cup_position(env) is None
    np.testing.assert_array_equal(avoiding_path(env), inner.rollout_path(inner.action_map.theta0))
    seed = next(s for s in range(10_000, 10_100) if env.reset(seed=s)[0][10] > 0.5)
    observation, _ = env.reset(seed=seed)
    cup = cup_position(env)
    np.testing.assert_allclose(cup, observation[11:13], atol=1e-6)          # the observation's cup fields
    free = inner.rollout_path(inner.action_map.theta0)
    steered = avoiding_path(env)
    np.testing.assert_array_equal(steered, avoiding_path(env, cup))
    clearance = np.linalg.norm(steered[:, :2] - cup, axis=1).min()
    assert clearance > np.linalg.norm(free[:, :2] - cup, axis=1).min() + 5e-3
