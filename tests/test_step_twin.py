"""The v3 step twin runs the episodic env's simulation core: action 0 is the episodic imitation, exactly; the step
ids keep their published observation and action spaces."""

from __future__ import annotations

import hashlib

import gymnasium as gym
import numpy as np
import pytest
import rdmp_gym.envs  # noqa: F401  (registers the ids)
from rdmp_gym.envs.coupling import coupling_filter
from rdmp_gym.envs.rhythmic_step import RhythmicTaskStepEnv
from rdmp_gym.envs.tasks.wiping.step import WipeStepBook, WipeStepEnv

SHORT = {"n_periods": 2.0}


def _twin_episode(env: gym.Env, seed: int, action: np.ndarray) -> tuple[float, dict, int]:
    env.reset(seed=seed)
    total, steps, done = 0.0, 0, False
    while not done:
        _, reward, terminated, truncated, info = env.step(action)
        total, steps, done = total + reward, steps + 1, terminated or truncated
    return total, info, steps


@pytest.mark.parametrize("seed", [7001, 7003])
def test_zero_action_is_the_episodic_imitation(seed):
    episodic = gym.make("rdmp_gym/ArmarWipe-v3", **SHORT)
    twin = gym.make("rdmp_gym/ArmarWipeStep-v3", **SHORT)
    episodic.reset(seed=seed)
    _, reward, _, _, info = episodic.step(np.zeros(episodic.action_space.shape, np.float32))
    total, last, steps = _twin_episode(twin, seed, np.zeros(3))
    assert steps == episodic.unwrapped.n_steps
    assert total == pytest.approx(reward, abs=1e-9)
    assert last["is_success"] == info["is_success"] and last["failure_causes"] == info["failure_causes"]
    for key in ("coverage", "peak_joint_accel", "jerk_ratio", "force_in_band_fraction", "obstacle_shift"):
        assert last[key] == info[key], key


def test_a_constant_action_shifts_the_path_by_max_shift():
    """The coupling's filter is critically damped with unit static gain: a held input c = alpha_z beta_z s settles
    at the shift s without overshoot."""
    transition, gain = coupling_filter(omega=2 * np.pi, alpha_z=5.0, dt=0.01)
    state = np.zeros(2)
    trace = []
    for _ in range(2000):
        state = transition @ state + gain * (5.0 * 5.0 / 4.0 * 0.03)
        trace.append(state[0])
    assert trace[-1] == pytest.approx(0.03, rel=1e-9)
    assert max(trace) <= 0.03 * (1 + 1e-9)


def test_a_shifted_episode_moves_the_sponge_and_stays_finite():
    twin = gym.make("rdmp_gym/ArmarWipeStep-v3", **SHORT)
    total, info, _ = _twin_episode(twin, 7003, np.array([0.0, 1.0, 0.0]))
    assert np.isfinite(total) and "is_success" in info
    path = twin.unwrapped._path
    imitation = twin.unwrapped.task.rollout_path(twin.unwrapped.task.action_to_params(
        np.zeros(twin.unwrapped.task.action_space.shape)))
    assert np.max(path[:, 1] - imitation[:, 1]) == pytest.approx(0.06, abs=0.01)


@pytest.mark.parametrize(("key", "value"), [("cup_clearance", 0.01), ("record_frames", True), ("reward_every", 2)])
def test_settings_it_cannot_honour_are_refused_by_name(key, value):
    with pytest.raises(ValueError, match=key):
        gym.make("rdmp_gym/ArmarWipeStep-v3", **SHORT, **{key: value})


def test_the_wiping_step_env_is_a_deprecated_name_of_the_generic_twin():
    with pytest.warns(DeprecationWarning, match="WipeStepEnv"):
        env = WipeStepEnv(version=3, **SHORT)
    assert isinstance(env, RhythmicTaskStepEnv) and isinstance(env.book, WipeStepBook)
    with pytest.warns(DeprecationWarning), pytest.raises(ValueError, match="cup_clearance"):
        WipeStepEnv(version=3, cup_clearance=0.01, **SHORT)


#: the published step ids' spaces: observation size and the digest of the observation's and the action's bounds
SPACES = {"rdmp_gym/ArmarWipeStep-v1": (26, "8cc093141bc9378c"), "rdmp_gym/ArmarWipeStep-v2": (26, "8cc093141bc9378c"),
          "rdmp_gym/ArmarWipeStep-v3": (26, "8cc093141bc9378c"), "rdmp_gym/PandaWipeStep-v3": (26, "8cc093141bc9378c"),
          "rdmp_gym/ArmarDrumStep-v1": (15, "02ae886d185139e7"), "rdmp_gym/PandaDrumStep-v1": (15, "02ae886d185139e7")}


@pytest.mark.parametrize("env_id", sorted(SPACES))
def test_the_step_ids_keep_their_observation_and_action_spaces(env_id):
    if env_id.startswith("rdmp_gym/Panda"):
        pytest.importorskip("gymnasium_robotics")
    env = gym.make(env_id).unwrapped
    observation, action = env.observation_space, env.action_space
    size, digest = SPACES[env_id]
    assert observation.shape == (size,) and observation.dtype == action.dtype == np.float32
    assert action.shape == (3,) and np.all(action.low == -1.0) and np.all(action.high == 1.0)
    context = env.task.observation_space
    np.testing.assert_array_equal(observation.high[-context.shape[0]:], np.maximum(-context.low, context.high))
    assert np.all(observation.low == -observation.high)
    bounds = hashlib.sha256(b"".join(np.ascontiguousarray(bound).tobytes() for space in (observation, action)
                                     for bound in (space.low, space.high)))
    assert bounds.hexdigest()[:16] == digest
    env.close()


def test_bad_actions_and_order_are_errors():
    twin = gym.make("rdmp_gym/ArmarWipeStep-v3", **SHORT).unwrapped
    with pytest.raises(RuntimeError, match="reset"):
        twin.step(np.zeros(3))
    twin.reset(seed=0)
    with pytest.raises(ValueError, match="shape"):
        twin.step(np.zeros(4))
    with pytest.raises(ValueError, match="NaN"):
        twin.step(np.array([np.nan, 0.0, 0.0]))
