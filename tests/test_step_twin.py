"""The v3 step twin runs the episodic env's simulation core: action 0 is the episodic imitation, exactly."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import rdmp_gym.envs  # noqa: F401  (registers the ids)
from rdmp_gym.envs.tasks.wiping.step import WipeStepEnv, coupling_filter

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


@pytest.mark.parametrize(("key", "value"), [("cup_clearance", 0.01), ("record_frames", True)])
def test_settings_it_cannot_honour_are_refused_by_name(key, value):
    with pytest.raises(ValueError, match=key):
        WipeStepEnv(version=3, **{key: value})


def test_bad_actions_and_order_are_errors():
    twin = gym.make("rdmp_gym/ArmarWipeStep-v3", **SHORT).unwrapped
    with pytest.raises(RuntimeError, match="reset"):
        twin.step(np.zeros(3))
    twin.reset(seed=0)
    with pytest.raises(ValueError, match="shape"):
        twin.step(np.zeros(4))
    with pytest.raises(ValueError, match="NaN"):
        twin.step(np.array([np.nan, 0.0, 0.0]))
