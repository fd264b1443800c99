"""Cheap strategies that tried to game ArmarWipe-v0 (issue 8) each score clearly below the imitation in v1.

Each test runs the imitation (action 0) and the cheap strategy in the same context. "Clearly below"
means at least 0.3 below (the imitation scores 0.9-1.2 on these contexts), a third of the coverage term's range.
The figures in the docstrings are measured with the smooth core (issue 7) and the env's defaults.
"""

import gymnasium as gym
import numpy as np
import probes
import pytest
import rdmp_gym.envs  # noqa: F401  (registers the env)
from rdmp_gym.envs import ENV_ID
from rdmp_gym.envs.tasks.wiping.scene import TablePose, table_frame

MARGIN = 0.3
NOMINAL = {"table_height": 0.0, "table_tilt": [0.0, 0.0], "patch_centre": [0.0, 0.0], "patch_size": [0.10, 0.10],
           "sponge_start": [-0.07, 0.22, 0.12], "obstacle": 0}


@pytest.fixture(scope="module")
def env():
    environment = gym.make(ENV_ID, n_periods=3.0)
    environment.reset(seed=0)          # gymnasium's passive checker must see a successful first reset
    yield environment
    environment.close()


def imitation(env, options, seed=0):
    env.reset(seed=seed, options=options)
    _, reward, _, _, info = env.step(np.zeros(env.action_space.shape, dtype=np.float32))
    return reward, info


def test_dirt_lives_on_the_table_only(env):
    """Item 1: a patch over the table's near edge is refused; a patch touching the edge has every cell on the top."""
    with pytest.raises(ValueError, match="beyond the table"):
        env.reset(options={**NOMINAL, "patch_centre": [-0.15, 0.0], "patch_size": [0.12, 0.12]})
    env.reset(options={**NOMINAL, "patch_centre": [-0.08, 0.0], "patch_size": [0.12, 0.12]})
    u = env.unwrapped
    origin, rot = table_frame(u.task.parts, TablePose.of(u.context))
    local = (u.task.dirt_cells(u.context) - origin) @ rot
    x_lo, x_hi, y_lo, y_hi = u.task.parts.table_extent
    assert np.all((local[:, 0] > x_lo) & (local[:, 0] < x_hi) & (local[:, 1] > y_lo) & (local[:, 1] < y_hi))
    assert np.abs(local[:, 2]).max() < 1e-12
    # sampled contexts never put dirt beyond the table either (the sampling ranges are checked at construction)
    for seed in range(20):
        obs, _ = env.reset(seed=seed)
        assert obs[3] - obs[5] / 2 >= x_lo - 1e-6


def test_holding_still_wipes_little(env):
    """Item 3: parking the pressed sponge on the patch (v0: coverage 0.80, reward 0.996 ~ the imitation)."""
    reward0, info0 = imitation(env, NOMINAL)
    reward, info = env.unwrapped.run_path(probes.hold_still(env.unwrapped))
    assert info["valid"] and info["force_in_band_fraction"] > 0.9      # it does press with the right force ...
    assert info["coverage"] < 0.5 * info0["coverage"]                  # ... but pressing is not wiping
    assert reward < reward0 - MARGIN


def test_press_and_lift_on_a_grid_loses(env):
    """Item 3: press-hold-lift on a 3x3 grid over a 0.22 m patch (v0: coverage 0.93, beat the imitation)."""
    options = {**NOMINAL, "patch_size": [0.22, 0.22]}
    reward0, info0 = imitation(env, options)
    reward, info = env.unwrapped.run_path(probes.press_lift_grid(env.unwrapped))
    assert info["valid"]
    assert info["coverage"] < info0["coverage"]
    assert reward < reward0 - MARGIN


def test_reaching_into_the_robot_is_stopped_and_charged(env):
    """Item 2: the arm collides with the robot's own torso (v0: passed through it); deep penetration voids
    the episode."""
    reward0, _ = imitation(env, NOMINAL)
    u = env.unwrapped
    start = int(np.argmax(u.task.periodic))
    path = probes._blend(probes._imitation(u), np.tile([-0.30, 0.28, 0.15], (u.n_steps, 1)), start, 250)
    reward, info = u.run_path(path)
    assert info["self_collision_fraction"] > 0.2
    assert info["penetration"] < 0.005                               # the torso stops the forearm
    assert info["reward_terms"]["self_collision"] < -0.2
    assert reward < reward0 - MARGIN
    strict = gym.make(ENV_ID, n_periods=3.0, penetration_limit=0.0002).unwrapped
    strict.reset(seed=0, options=NOMINAL)
    reward, info = strict.run_path(path)
    assert info["valid"] is False and info["invalid_reason"] == "penetration" and reward <= -1.0


def smooth_twin(env, action):
    """``action`` without its weight entries: the same initial condition, amplitude and approach, so the
    same pattern size and coverage, but none of the random weights' wiggles."""
    twin = action.copy()
    for name in ("periodic", "transient:0"):
        twin[env.unwrapped.action_map.slices[name]] = 0.0
    return twin


@pytest.mark.parametrize("seed", [0, 1])
def test_random_jagged_actions_lose(env, seed):
    """Item 7: uniformly random actions (v0: beat the imitation on 11 of 20 contexts).

    Under the smooth core a random action's path is 7-25x as jerky as the imitation's (20 contexts; its
    smooth twin 0.6-2.1x), hence ``jerk_ratio > 5`` and a smoothness charge of at least ``0.25 ln 5 = 0.4``.
    Over 20 contexts it scores >= 0.58 below the imitation and >= 0.49 below its twin (the slow test).
    Its random amplitude can cover more than the imitation (0.80 vs 0.72 at seed 0), so it must also lose
    to its smooth twin with the same coverage (within 0.03): a jagged policy scores below a smooth one.
    """
    options = {"obstacle": 0}
    reward0, _ = imitation(env, options, seed)
    action = np.random.default_rng(seed).uniform(-1, 1, env.action_space.shape).astype(np.float32)
    env.reset(seed=seed, options=options)
    _, reward, _, _, info = env.step(action)
    env.reset(seed=seed, options=options)
    _, smooth, _, _, twin = env.step(smooth_twin(env, action))
    assert info["jerk_ratio"] > 5.0 and twin["jerk_ratio"] < 0.5 * info["jerk_ratio"]
    assert info["reward_terms"]["smoothness"] < -0.4
    assert abs(info["coverage"] - twin["coverage"]) < 0.03
    assert reward < reward0 - MARGIN
    assert reward < smooth - MARGIN


def test_alternating_weights_lose(env):
    """Item 7: alternating +-1 actions (v0: 0.964 vs 0.974).

    The smooth core's wide, overlapping basis averages neighbouring weights, so alternating weights no
    longer make a violent path (peak joint acceleration 8.8 rad/s², was 83; jerk ratio 15, was 256): it
    is a rough, shrunken wipe with a lowered approach (coverage 0.66 vs 0.72), charged for its jerk
    (``jerk_ratio > 5``), and its joints accelerate more than twice as hard as the imitation's (3.0 rad/s²).
    """
    reward0, info0 = imitation(env, {"obstacle": 0})
    action = np.where(np.arange(env.action_space.shape[0]) % 2 == 0, 1.0, -1.0).astype(np.float32)
    env.reset(seed=0, options={"obstacle": 0})
    _, reward, _, _, info = env.step(action)
    assert info["jerk_ratio"] > 5.0 and info["reward_terms"]["smoothness"] < -0.4
    assert info["peak_joint_accel"] > 2.0 * info0["peak_joint_accel"]
    assert reward < reward0 - MARGIN


def test_knocking_the_cup_loses_and_the_approach_matters(env):
    """Item 8: the imitation's approach knocks the cup in the corridor; raising the approach over it wins.

    The raised approach is an action: the ``approach`` dimension at +1 (a smooth 6 cm lift of the DMP's
    own transient, see ``envs/tasks/wiping/approach.py``) clears the cup with success, where the imitation fails.
    It pays for its extra jerk (2.0x the imitation's: -0.17) and wins by 0.76 (1.00 vs 0.24).
    """
    options = {**NOMINAL, "obstacle": 1}
    obs, _ = env.reset(seed=0, options=options)
    assert obs[10] == 1.0 and np.linalg.norm(obs[11:13]) > 0                # the cup is in the observation
    clear, _ = imitation(env, {**options, "obstacle": 0})
    knocked, info = imitation(env, options)
    assert info["obstacle_touch_steps"] > 0 and info["obstacle_shift"] > 0.02
    assert info["is_success"] is False and info["reward_terms"]["obstacle"] <= -0.5
    assert knocked < clear - MARGIN
    touch = np.flatnonzero(info["cost_terms"]["obstacle"])
    assert touch.size and touch[0] < int(np.argmax(env.unwrapped.task.periodic))   # charged in the approach
    lift = np.zeros(env.action_space.shape, dtype=np.float32)
    lift[-1] = 1.0                                                          # the approach dimension
    env.reset(seed=0, options=options)
    _, lifted, _, _, info = env.step(lift)
    assert info["obstacle_touch_steps"] == 0 and info["obstacle_shift"] < 0.005 and info["is_success"] is True
    assert info["reward_terms"]["smoothness"] < 0                           # the lift is not free ...
    assert lifted > knocked + 2 * MARGIN                                    # ... but pays off clearly


def test_a_hard_touchdown_is_charged_when_it_happens(env):
    """Item 6: the peak force within 0.2 s of the first contact above 40 N costs, at the step of the peak."""
    reward0, info0 = imitation(env, NOMINAL)
    assert info0["reward_terms"]["impact"] == 0.0
    u = env.unwrapped
    path = u.rollout_path(u.action_map.theta0)
    z = path[:, 2]
    k = int(np.flatnonzero(z < 0.05)[0])
    steps = np.arange(len(z))
    path[:, 2] = np.where(steps >= k, np.interp(steps, [k, k + 12], [z[k], -0.03]), z)   # slam 3 cm into it
    reward, info = u.run_path(path)
    assert info["valid"] and info["impact_force"] > 60.0
    impact = info["cost_terms"]["impact"]
    assert np.count_nonzero(impact) == 1 and int(np.flatnonzero(impact)[0]) < k + 40
    assert info["reward_terms"]["impact"] < -0.1
    assert reward < reward0 - MARGIN


@pytest.mark.slow
def test_random_actions_lose_on_twenty_contexts():
    """Item 7 in full (v0: random actions beat the imitation on 11 of 20 contexts; v1: on none), and each
    loses to its smooth twin with the same coverage."""
    environment = gym.make(ENV_ID, n_periods=4.0)
    for seed in range(20):
        reward0, _ = imitation(environment, {"obstacle": 0}, seed)
        action = np.random.default_rng(seed).uniform(-1, 1, environment.action_space.shape).astype(np.float32)
        environment.reset(seed=seed, options={"obstacle": 0})
        _, reward, _, _, info = environment.step(action)
        environment.reset(seed=seed, options={"obstacle": 0})
        _, smooth, _, _, twin = environment.step(smooth_twin(environment, action))
        assert reward < reward0 - MARGIN, seed
        assert abs(info["coverage"] - twin["coverage"]) < 0.03 and reward < smooth - MARGIN, seed


@pytest.mark.slow
@pytest.mark.parametrize("tilt", [(0.15, 0.0), (-0.15, 0.0), (0.0, 0.15), (0.0, -0.15), (0.15, 0.15),
                                  (-0.15, -0.15), (0.15, -0.15), (-0.15, 0.15)])
def test_coverage_over_the_full_tilt_range(tilt):
    """Item 5 in full: action 0 keeps the coverage within 10 % of the level table at every tilt extreme, in a
    valid episode (at (-0.15, -0.15) the forearm used to enter the torso by 9 mm)."""
    environment = gym.make(ENV_ID, n_periods=4.0)
    options = {**NOMINAL, "patch_size": [0.12, 0.12]}
    _, level = imitation(environment, options)
    _, tilted = imitation(environment, {**options, "table_tilt": list(tilt)})
    assert tilted["valid"] and tilted["penetration"] == 0.0 and tilted["self_collision_fraction"] == 0.0
    assert tilted["coverage"] >= 0.9 * level["coverage"]
    assert tilted["force_in_band_fraction"] >= 0.95
