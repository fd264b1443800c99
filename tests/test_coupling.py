"""Obstacle avoidance coupling (rdmp_gym.dmp.coupling): properties of the steering term and a core-only wiping
scenario."""

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from rdmp_gym import RhythmicDMP, wiping_demonstration
from rdmp_gym.dmp.coupling import AdaptiveLift, LiftOver, ObstacleAvoidance, avoiding_rollout, spring_stiffness

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
    from obstacle_baseline import run_avoiding
    from rdmp_gym.envs import ENV_ID

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
    from obstacle_baseline import avoiding_path, cup_position
    from rdmp_gym.envs import ENV_ID

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


# ---------------------------------------------------------------- lifting over a volume (the cup)
def lift(**kwargs):
    settings = dict(centre=[0.1, 0.0], top=0.08, radius=0.035, reach=0.07, stiffness=100.0, clearance=0.01,
                    ramp=0.15, window=(0.5, 1.0, 1.5))
    return LiftOver(**{**settings, **kwargs})


@settings(max_examples=200, deadline=None, database=None, derandomize=True)
@given(vectors, vectors, st.floats(-1.0, 3.0))
def test_lift_acts_upwards_only_within_its_footprint_and_window(y, v, time):
    term = lift()
    p = term.acceleration(y, v, time=time)
    assert np.all(np.isfinite(p)) and p[0] == p[1] == 0.0
    assert 0.0 <= p[2] <= term.stiffness * term.lift * (1.0 + 1e-12)
    rho = np.hypot(y[0] - 0.1, y[1])
    if rho >= term.radius + term.reach + term.ramp or time <= 0.0 or time >= 1.5:
        assert p[2] == 0.0
    if rho <= term.radius + term.reach and 0.5 <= time <= 1.0:
        assert p[2] == pytest.approx(term.stiffness * term.lift)                 # the full lift: top + clearance


def test_lift_is_smooth_in_space_and_time():
    term = lift()
    rho = np.linspace(0.0, 0.4, 4001)
    heights = term.height(np.c_[0.1 + rho, np.zeros_like(rho), np.zeros_like(rho)])
    slope = np.diff(heights) / np.diff(rho)
    assert np.all(slope <= 1e-12)                                               # falls off monotonically
    assert np.abs(slope).max() <= 1.875 * term.lift / term.ramp * (1.0 + 1e-3)   # the minimum-jerk step's peak slope
    times = np.linspace(-0.5, 2.0, 2501)
    gate = term.gate(times)
    assert gate[0] == 0.0 and gate[-1] == 0.0 and gate.max() == 1.0
    assert np.abs(np.diff(gate, 2)).max() < 1e-4                                # no kink: C2 steps


def test_lift_checks_its_input():
    for bad, name in ((dict(centre=[0.0]), "centre"), (dict(centre=[np.nan, 0.0]), "centre"),
                      (dict(top=-0.01), "top"), (dict(radius=0.0), "radius"), (dict(reach=-0.01), "reach"),
                      (dict(clearance=np.inf), "clearance"), (dict(stiffness=np.nan), "stiffness"),
                      (dict(window=(1.0, 0.5, 2.0)), "window"), (dict(window=(0.5, 1.0)), "window"),
                      (dict(dims=(0, 0, 2)), "dims")):
        with pytest.raises(ValueError, match=name):
            lift(**bad)
    with pytest.raises(ValueError, match="time"):
        lift().acceleration(np.zeros(3), np.zeros(3))                            # the window needs the time
    with pytest.raises(ValueError, match="y"):
        lift().acceleration(np.zeros(2), np.zeros(2), time=0.7)
    assert lift(window=None).acceleration(np.array([0.1, 0.0, 0.0]), np.zeros(3))[2] > 0.0


def test_lift_raises_the_approach_and_leaves_the_wiping_unchanged(wiping):
    t = np.arange(0.0, 8.0, 2e-3)
    start = np.array([0.0, 0.20, 0.10])
    free, free_velocity = wiping.rollout(t, y0=start, return_velocity=True)
    length = wiping.transients[0].length
    # a cup halfway along the approach, its top at the free path's height there
    k = np.argmin(np.abs(t - 0.5 * length))
    term = LiftOver(free[k, :2], free[k, 2] + 0.03, 0.035, 0.06, spring_stiffness(wiping), clearance=0.01,
                    window=(0.35 * length, 0.6 * length, 0.88 * length))
    y, yd = avoiding_rollout(wiping, t, term, y0=start)
    assert np.all(np.isfinite(y))
    assert np.min(term.clearance_of(free[t < length])) < 0.0                    # the free approach runs into it
    assert np.min(term.clearance_of(y[t < length])) > 0.0                       # the lifted one passes above
    assert np.abs(y[:, :2] - free[:, :2]).max() < 1e-6                          # only the height moves
    later = t > length + 0.5 * wiping.period
    assert np.abs(y[later] - free[later]).max() < 1e-5                          # the wiping is the DMP's own

    def squared_jerk(velocity):
        return np.sum(np.gradient(np.gradient(velocity, 2e-3, axis=0), 2e-3, axis=0) ** 2)

    assert squared_jerk(yd) < 2.0 * squared_jerk(free_velocity)


def test_adaptive_lift_raises_only_as_far_as_needed(wiping):
    t = np.arange(0.0, 8.0, 2e-3)
    start = np.array([0.0, 0.20, 0.10])
    free, free_velocity = wiping.rollout(t, y0=start, return_velocity=True)
    length = wiping.transients[0].length
    k = np.argmin(np.abs(t - 0.5 * length))
    window = (0.35 * length, 0.6 * length, 0.88 * length)
    volume = LiftOver(free[k, :2], free[k, 2] + 0.03, 0.035, 0.06, spring_stiffness(wiping), clearance=0.02,
                      window=window)
    term = AdaptiveLift(volume)
    y, yd = avoiding_rollout(wiping, t, term, y0=start)
    fixed, _ = avoiding_rollout(wiping, t, volume, y0=start)
    approach = t < length
    assert np.min(volume.clearance_of(free[approach])) < 0.0 < np.min(volume.clearance_of(y[approach]))
    assert np.max(y[:, 2] - free[:, 2]) < 0.95 * np.max(fixed[:, 2] - free[:, 2])    # less than the full lift
    later = t > length + 0.5 * wiping.period
    assert np.abs(y[later] - free[later]).max() < 1e-5 and np.abs(y[:, :2] - free[:, :2]).max() < 1e-6

    def squared_jerk(velocity):
        return np.sum(np.gradient(np.gradient(velocity, 2e-3, axis=0), 2e-3, axis=0) ** 2)

    assert squared_jerk(yd) < 2.0 * squared_jerk(free_velocity)
    # its copy of the shift is the shift the rollout shows (the transformation system is linear)
    middle = t <= 0.7 * length
    part, _ = avoiding_rollout(wiping, t[middle], term, y0=start)
    assert abs(term.shift - (part[-1, 2] - free[middle][-1, 2])) < 1e-3 * (part[-1, 2] - free[middle][-1, 2])
    # away from the volume's footprint it does nothing
    far = AdaptiveLift(LiftOver([1.0, 1.0], 0.1, 0.035, 0.06, spring_stiffness(wiping), window=window))
    assert not np.any(far.acceleration(free[k], free_velocity[k], time=t[k]))
    np.testing.assert_allclose(avoiding_rollout(wiping, t, far, y0=start)[0], free, atol=1e-9)


def test_adaptive_lift_checks_its_input():
    with pytest.raises(TypeError, match="volume"):
        AdaptiveLift(ObstacleAvoidance([0.0, 0.0]))
    with pytest.raises(ValueError, match="lead"):
        AdaptiveLift(lift(), lead=-0.1)
    with pytest.raises(ValueError, match="width"):
        AdaptiveLift(lift(), width=0.0)
    term = AdaptiveLift(lift())
    with pytest.raises(ValueError, match="time"):
        term.acceleration(np.zeros(3), np.zeros(3))
    term.acceleration(np.zeros(3), np.zeros(3), time=0.7)
    with pytest.raises(ValueError, match="time"):
        term.acceleration(np.zeros(3), np.zeros(3), time=0.6)                   # back in time
    assert np.all(np.isfinite(term.acceleration(np.array([0.1, 0.0, 0.0]), np.ones(3), time=0.8)))


def test_env_coupling_baseline_lifts_over_the_cup():
    gym = pytest.importorskip("gymnasium")
    from obstacle_baseline import coupling_baseline_scores, lift_term, lifting_path
    from rdmp_gym.envs import ENV_ID

    env = gym.make(ENV_ID)
    inner = env.unwrapped
    cup_seed, free_seed = 2**30 + 2, 2**30                     # the agents protocol's test contexts, with and without
    env.reset(seed=free_seed)
    imitation_return = env.step(np.zeros(env.action_space.shape, dtype=np.float32))[1]
    env.reset(seed=cup_seed)
    imitation_cup = env.step(np.zeros(env.action_space.shape, dtype=np.float32))[4]
    assert imitation_cup["obstacle_touch_steps"] > 0                              # the imitation hits the cup
    scores = coupling_baseline_scores(env, np.array([free_seed, cup_seed]))
    assert scores["cup"].tolist() == [False, True]
    assert scores["returns"][0] == imitation_return and scores["jerk_ratio"][0] == 1.0   # no cup: the imitation
    assert scores["valid"].all() and not scores["cup_touched"].any() and scores["cup_shift"].max() < 1e-3
    assert 1.0 < scores["jerk_ratio"][1] <= 2.0
    assert scores["coverage"][1] >= imitation_cup["coverage"] - 0.02
    env.reset(seed=cup_seed)
    path, free = lifting_path(env), inner.rollout_path(inner.action_map.theta0)
    term = lift_term(env)
    assert np.min(term.clearance_of(free)) < 0.0 < np.min(term.clearance_of(path[inner.times < 2.0]))
    assert path[:, 2].max() <= free[:, 2].max() + 1e-3           # lifted only where the free approach is low
    later = inner.times > inner.dmp.transients[0].length + 0.5 * inner.dmp.period
    assert np.abs(path[later] - free[later]).max() < 1e-4                         # the wiping unchanged
    for bad in (np.array([]), np.array([0.5]), np.array([[1, 2]])):
        with pytest.raises(ValueError, match="seeds"):
            coupling_baseline_scores(env, bad)
