"""The cup clearance term of the wiping env: the push keeps the hand's points off the cup, is smooth and bounded,
changes nothing without a cup, and bad settings get clear errors."""

import gymnasium as gym
import numpy as np
import pytest
from rdmp_gym.agents.protocol import path_jerk
from rdmp_gym.envs import ENV_ID_V2
from rdmp_gym.envs.tasks.wiping.clearance import Cup, CupClearance

CUP = Cup(base=np.zeros(3), radius=0.035, top=0.08)
DT = 0.01                                      # s per control step of the synthetic paths
#: a reset seed of ArmarWipe-v2 whose imitation knocks the cup beside its patch (40 control steps)
TOUCHING_SEED = 13


def _line(offset: float, steps: int = 400, height: float = 0.02) -> np.ndarray:
    """``[T, 1, 3]`` one point passing the cup along x at ``offset`` (m) from its axis."""
    x = np.linspace(-0.3, 0.3, steps)
    return np.stack([x, np.full(steps, offset), np.full(steps, height)], axis=1)[:, None, :]


def _gaps(points: np.ndarray) -> np.ndarray:
    return np.linalg.norm(points[..., :2], axis=-1).min(axis=1)


def test_push_keeps_the_margin_and_is_smooth():
    clearance = CupClearance(margin=0.01, smoothing=0.25)
    points = _line(0.03)
    push = clearance.push(points, CUP, np.eye(3), DT)
    assert np.all(push[:, 2] == 0.0)
    assert _gaps(points + push[:, None]).min() >= CUP.radius + clearance.margin - 1e-6
    assert np.linalg.norm(push, axis=1).max() <= clearance.max_push
    # a Gaussian spread: far from the steps that need a push there is none, and the push has no kinks
    needing = np.flatnonzero(_gaps(points) < CUP.radius + clearance.margin)
    far = np.abs(np.arange(len(points))[:, None] - needing[None]).min(axis=1) > 6 * clearance.smoothing / DT
    assert np.abs(push[far]).max() < 1e-6
    second = np.abs(np.diff(push[:, 1], 2)).max()
    assert second < 4 * np.abs(push[:, 1]).max() / (clearance.smoothing / DT) ** 2


def test_no_push_where_the_hand_is_clear_or_above_the_cup():
    clearance = CupClearance()
    assert not np.any(clearance.push(_line(0.2), CUP, np.eye(3), DT))
    assert not np.any(clearance.push(_line(0.0, height=CUP.top + 0.05), CUP, np.eye(3), DT))


def test_push_is_bounded_where_the_needs_disagree():
    clearance = CupClearance(max_push=0.03)
    push = clearance.push(_line(0.0), CUP, np.eye(3), DT)     # straight over the cup's centre: away flips sides
    assert np.all(np.isfinite(push)) and np.linalg.norm(push, axis=1).max() <= 0.03 + 1e-12


@pytest.mark.parametrize("kwargs, name", [({"margin": 0.0}, "margin"), ({"smoothing": -1.0}, "smoothing"),
                                          ({"max_push": float("nan")}, "max_push"), ({"iterations": 0}, "iterations"),
                                          ({"iterations": True}, "iterations"), ({"margin": "1cm"}, "margin")])
def test_bad_settings_name_the_field(kwargs, name):
    with pytest.raises(ValueError, match=name):
        CupClearance(**kwargs)


@pytest.mark.parametrize("value", [-0.01, 0.0, True, "1cm", float("inf")])
def test_bad_env_argument_names_it(value):
    with pytest.raises(ValueError, match="cup_clearance"):
        gym.make(ENV_ID_V2, cup_clearance=value)


@pytest.fixture(scope="module")
def envs():
    plain, guarded = gym.make(ENV_ID_V2), gym.make(ENV_ID_V2, cup_clearance=0.01)
    yield plain, guarded
    plain.close()
    guarded.close()


def _has_cup(env, seed):
    env.reset(seed=seed)
    return env.unwrapped.context.obstacle


def _run(env, seed):
    env.reset(seed=seed)
    return env.step(np.zeros(env.action_space.shape, dtype=np.float32))[1:5:3]


def test_clearance_keeps_the_imitation_off_a_cup_it_knocks(envs):
    plain, guarded = envs
    reward, info = _run(plain, TOUCHING_SEED)
    assert plain.unwrapped.context.obstacle and info["obstacle_touch_steps"] > 10
    guarded_reward, guarded_info = _run(guarded, TOUCHING_SEED)
    assert guarded_info["obstacle_touch_steps"] == 0 and "cup" not in guarded_info["failure_causes"]
    assert 0.0 < guarded_info["clearance_push"] <= 3 * guarded.unwrapped.task.cup_clearance.max_push
    assert abs(guarded_info["coverage"] - info["coverage"]) < 0.01 and guarded_reward > reward
    assert _run(guarded, TOUCHING_SEED)[0] == guarded_reward                    # the same seed, the same numbers
    base = guarded.unwrapped
    theta = base.action_map.theta0
    executed = base.executed_path(np.zeros(base.action_space.shape))            # the action of theta0
    np.testing.assert_array_equal(executed, base.task.executed_path(theta, base.context))
    shift = np.linalg.norm(executed - base.rollout_path(theta), axis=1).max()
    assert shift == pytest.approx(guarded_info["clearance_push"])
    gaps = base.task.hand_cup_gaps(executed, base.context)
    assert set(gaps) == {"fingers", "thumb", "palm", "sponge"}
    assert all(gap.shape == (base.n_steps,) for gap in gaps.values())
    before = min(g.min() for g in base.task.hand_cup_gaps(base.rollout_path(theta), base.context).values())
    after = min(g.min() for g in gaps.values())
    assert before < 0.0 < after and after > 0.5 * base.task.cup_clearance.margin
    zeros = np.zeros(plain.action_space.shape)
    assert path_jerk(guarded, zeros, TOUCHING_SEED) != path_jerk(plain, zeros, TOUCHING_SEED)


def test_clearance_changes_nothing_without_a_cup(envs):
    plain, guarded = envs
    seed = next(s for s in range(50) if not _has_cup(plain, s))
    (reward, info), (guarded_reward, guarded_info) = _run(plain, seed), _run(guarded, seed)
    assert guarded_info["clearance_push"] == 0.0 and "clearance_push" not in info
    assert guarded_reward == reward and guarded_info["coverage"] == info["coverage"]
    u = guarded.unwrapped
    assert u.task.hand_cup_gaps(u.rollout_path(u.action_map.theta0), u.context) == {}
