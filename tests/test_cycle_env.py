"""The cycle-level face: one step per cycle on the episodic face's simulation core."""

import threading

import gymnasium as gym
import numpy as np
import pytest
import rdmp_gym.envs  # noqa: F401  (registers the ids)
from gymnasium.utils.env_checker import check_env
from rdmp_gym.envs.cycle_env import RhythmicCycleEnv
from rdmp_gym.envs.registration import cycle_id
from rdmp_gym.envs.tasks.description import Rejection

SEED = 11


@pytest.fixture(scope="module")
def wipe() -> RhythmicCycleEnv:
    env = gym.make("rdmp_gym/PandaWipeCycle-v3").unwrapped
    yield env
    env.close()


def _episode(env: RhythmicCycleEnv, actions) -> tuple[float, dict, list[np.ndarray]]:
    """Run one episode with ``actions(cycle) -> [n]``; (return, last info, observations)."""
    observation, _ = env.reset(seed=SEED)
    total, observations = 0.0, [observation]
    for cycle in range(env.n_cycles):
        observation, reward, terminated, _, info = env.step(actions(cycle))
        total += reward
        observations.append(observation)
        if terminated:
            return total, info, observations
    raise AssertionError("the episode did not end after its cycles")


@pytest.fixture(scope="module")
def zero_run(wipe):
    zero = np.zeros(wipe.action_space.shape)
    total, info, observations = _episode(wipe, lambda cycle: zero)
    return total, info, observations, wipe.face.solution.plan.path.copy(), wipe.face.live_targets.q.copy()


def test_every_task_has_a_cycle_face_on_every_robot():
    from rdmp_gym.envs.registration import ROBOT_ID_NAMES, task_ids
    from rdmp_gym.envs.tasks import TASKS

    for task, entry in TASKS.items():
        for robot in ROBOT_ID_NAMES:
            episodic = task_ids(task, robot, max(entry.versions))[0]
            if episodic in gym.registry:
                assert cycle_id(episodic) in gym.registry, episodic
    assert "rdmp_gym/ArmarWipeCycle-v2" not in gym.registry           # the earlier versions keep their faces


def test_the_zero_action_in_every_cycle_is_the_episodic_action_zero_bit_for_bit(wipe, zero_run):
    total, info, observations, _, _ = zero_run
    episodic = gym.make("rdmp_gym/PandaWipe-v3")
    episodic.reset(seed=SEED)
    _, reward, _, _, expected = episodic.step(np.zeros(episodic.action_space.shape))
    assert total == reward
    assert np.array_equal(info["cost_trace"], expected["cost_trace"])
    assert info["coverage"] == expected["coverage"] and info["is_success"] == expected["is_success"]
    assert info["cycles_run"] == wipe.n_cycles and len(observations) == wipe.n_cycles + 1


def test_drumming_cycles_with_the_zero_action_are_the_episodic_action_zero():
    env = gym.make("rdmp_gym/PandaDrumCycle-v1").unwrapped
    zero = np.zeros(env.action_space.shape)
    total, info, _ = _episode(env, lambda cycle: zero)
    episodic = gym.make("rdmp_gym/PandaDrum-v1")
    episodic.reset(seed=SEED)
    _, reward, _, _, expected = episodic.step(zero)
    assert total == reward and np.array_equal(info["cost_trace"], expected["cost_trace"])
    assert np.array_equal(info["strike_times"], expected["strike_times"])
    env.close()


def test_a_change_of_the_drum_rhythm_resumes_the_follower_where_the_cycle_starts():
    """A cycle that changes the beat's shift goes on from the follower's state at its start (the canonical time
    before it is the running one's); a later change of weights alone keeps that schedule."""
    env = gym.make("rdmp_gym/PandaDrumCycle-v1").unwrapped
    zero, shifted = np.zeros(env.action_space.shape), np.zeros(env.action_space.shape)
    shifted[-1] = 0.3
    reshaped = shifted.copy()
    reshaped[:5] = 0.05
    _episode(env, lambda cycle: zero)
    running = env.face.solution.plan.extras["schedule"]
    _, info, _ = _episode(env, lambda cycle: zero if cycle < 3 else shifted if cycle < 5 else reshaped)
    schedule, step = env._plan.extras["schedule"], int(env.start_steps[3])
    assert schedule.since == step and not info["refused"]
    np.testing.assert_array_equal(schedule.s[: step + 1], running.s[: step + 1])
    assert not np.array_equal(schedule.s[step + 50:], running.s[step + 50:])
    env.close()


def test_observations_hold_the_context_the_state_and_the_progress(wipe, zero_run):
    observations = zero_run[2]
    context_size = wipe.task.context_bounds()[0].size
    assert all(wipe.observation_space.contains(o) for o in observations)
    assert np.all([np.array_equal(o[:context_size], observations[0][:context_size]) for o in observations])
    progress = [o[-1] for o in observations[:-1]]
    assert progress[0] == 0.0 and np.all(np.diff(progress) > 0)
    dirt = [o[context_size + 6] for o in observations[:-1]]          # the dirt left falls as the sponge wipes
    assert dirt[0] == 1.0 and dirt[-1] < 0.5 * dirt[0]


def _jerk_peak(path: np.ndarray, dt: float) -> float:
    """The largest step-to-step change of acceleration of ``path [T, 3]`` (m/s^3)."""
    return float(np.abs(np.diff(path, n=3, axis=0)).max()) / dt**3


def test_a_change_keeps_what_was_executed_and_hands_over_smoothly(wipe, zero_run):
    _, _, _, zero_path, zero_targets = zero_run
    cycle, dt = 2, wipe.face.dt
    change = np.clip(0.05 * np.random.default_rng(0).standard_normal(wipe.action_space.shape), -1, 1)
    _, info, _ = _episode(wipe, lambda k: change if k >= cycle else np.zeros(wipe.action_space.shape))
    path, targets, step = wipe.face.solution.plan.path, wipe.face.live_targets.q, wipe.start_steps[cycle]
    assert info["refused"] == []
    assert np.array_equal(path[:step], zero_path[:step]) and np.array_equal(targets[:step - 1],
                                                                            zero_targets[:step - 1])
    assert np.abs(path[step:] - zero_path[step:]).max() > 1e-3
    # across the hand-over the path is no rougher than the rollouts of either parameters are of their own
    changed = wipe.face.plan(*wipe.face._split(change)).path
    around = slice(step - 5, step + round(wipe.handover / dt) + 5)
    assert _jerk_peak(path[around], dt) <= 1.2 * max(_jerk_peak(zero_path, dt), _jerk_peak(changed, dt))


def test_a_refused_change_leaves_the_cycle_as_it_was(wipe, zero_run, monkeypatch):
    imitation = wipe.face.action_map.theta0
    monkeypatch.setattr(wipe.task, "check_params",
                        lambda theta: None if np.array_equal(theta, imitation) else Rejection("r0", 0.5))
    zero = np.zeros(wipe.action_space.shape)
    total, info, _ = _episode(wipe, lambda k: zero if k < 3 else np.full(wipe.action_space.shape, 0.2))
    assert info["refused"] == [(k, "r0") for k in range(3, wipe.n_cycles)]
    assert total == zero_run[0]


def test_leaving_an_episode_ends_its_worker(wipe):
    before = threading.active_count()
    wipe.reset(seed=SEED)
    wipe.step(np.zeros(wipe.action_space.shape))
    assert threading.active_count() == before + 1
    wipe.reset(seed=SEED + 1)
    assert threading.active_count() == before
    with pytest.raises(RuntimeError, match="reset"):
        RhythmicCycleEnv(task="drum", robot="panda").step(np.zeros(1))


def test_bad_handover_is_refused():
    with pytest.raises(ValueError, match="handover"):
        RhythmicCycleEnv(task="drum", robot="panda", handover=0.0)


def test_gymnasium_and_sb3_checkers_pass():
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    env = gym.make("rdmp_gym/PandaWipeCycle-v3")
    check_env(env.unwrapped, skip_render_check=True)
    sb3_check_env(env.unwrapped, warn=True)
    env.close()
