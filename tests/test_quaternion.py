"""Quaternion maps: exp/log against scipy's rotations, q and -q, half and full turns, rates."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from rdmp_gym.dmp import quaternion as Q


def _scipy(v: np.ndarray) -> np.ndarray:
    xyzw = Rotation.from_rotvec(v).as_quat()
    return np.concatenate([xyzw[..., 3:], xyzw[..., :3]], axis=-1)


def _yaw(angles: np.ndarray) -> np.ndarray:
    return Q.exp_map(np.outer(angles, [0.0, 0.0, 1.0]))


def test_exp_and_log_agree_with_scipy_and_invert_each_other():
    v = np.random.default_rng(0).normal(0.0, 1.0, (200, 3))
    v = v[np.linalg.norm(v, axis=1) < np.pi]
    q = Q.exp_map(v)
    assert np.allclose(q, _scipy(v), atol=1e-14)
    assert np.allclose(Q.log_map(q), v, atol=1e-12)
    assert np.allclose(Q.log_map(Q.exp_map(np.full((1, 3), 1e-10))), 1e-10, rtol=1e-6)


def test_minus_q_is_the_far_branch_of_the_same_orientation():
    v = np.array([[0.3, -0.2, 0.5]])
    far = Q.log_map(-Q.exp_map(v))
    assert np.isclose(np.linalg.norm(far), 2.0 * np.pi - np.linalg.norm(v))
    assert np.allclose(Q.angle_between(Q.exp_map(far), Q.exp_map(v)), 0.0, atol=1e-7)
    assert np.allclose(Q.angle_between(Q.exp_map(v), -Q.exp_map(v)), 0.0)


def test_product_and_matrix_agree_with_scipy():
    a, b = np.random.default_rng(1).normal(0.0, 1.0, (2, 10, 3))
    product = _scipy((Rotation.from_rotvec(a) * Rotation.from_rotvec(b)).as_rotvec())
    assert np.max(Q.angle_between(Q.multiply(_scipy(a), _scipy(b)), product)) < 1e-7
    quarter = Q.from_matrix(np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]))
    assert np.allclose(quarter, [np.cos(np.pi / 4), 0.0, 0.0, np.sin(np.pi / 4)])


def test_sign_flips_are_removed_and_do_not_change_the_tangent():
    q = Q.exp_map(np.column_stack([0.2 * np.sin(np.linspace(0, 6, 300)), np.linspace(0, 0.4, 300),
                                   np.zeros(300)]))
    flipped = q * np.where(np.arange(300) % 2 == 0, 1.0, -1.0)[:, None]
    joined = Q.continuous(flipped)
    assert np.all(np.sum(joined[1:] * joined[:-1], axis=1) > 0.0)
    reference = Q.mean(flipped)
    assert np.allclose(Q.to_tangent(flipped, reference), Q.to_tangent(q, reference), atol=1e-12)
    assert np.allclose(Q.angular_velocity(flipped, 0.01), Q.angular_velocity(q, 0.01), atol=1e-9)


@pytest.mark.parametrize("reference_at", ["mean", "start"])
def test_a_half_turn_has_continuous_tangent_coordinates(reference_at):
    q = _yaw(np.linspace(0.0, np.pi, 500))
    reference = Q.mean(q) if reference_at == "mean" else q[0]
    v = Q.to_tangent(q, reference)
    largest = np.max(np.linalg.norm(v, axis=1))
    assert np.isclose(largest, np.pi / 2 if reference_at == "mean" else np.pi, atol=1e-9)
    assert np.max(np.linalg.norm(np.diff(v, axis=0), axis=1)) < 1.01 * np.pi / 499
    assert np.max(Q.angle_between(Q.from_tangent(v, reference), q)) < 1e-9


def test_past_a_half_turn_from_the_reference_the_far_branch_keeps_it_continuous():
    q = _yaw(np.linspace(0.0, 1.3 * np.pi, 500))
    v = Q.to_tangent(q, q[0])
    assert np.isclose(np.max(np.linalg.norm(v, axis=1)), 1.3 * np.pi)
    assert np.max(np.linalg.norm(np.diff(v, axis=0), axis=1)) < 1.01 * 1.3 * np.pi / 499


def test_a_full_turn_is_refused():
    with pytest.raises(ValueError, match="turns 324 deg"):
        Q.to_tangent(_yaw(np.linspace(0.0, 1.8 * np.pi, 100)), _yaw(np.zeros(1))[0])
    with pytest.raises(ValueError, match="all the way round"):
        Q.mean(_yaw(np.linspace(0.0, 4.0 * np.pi, 400, endpoint=False)))


def test_bad_quaternions_are_named():
    with pytest.raises(ValueError, match=r"q: row 1 has norm 0"):
        Q.check_unit(np.array([[1.0, 0, 0, 0], [0.0, 0, 0, 0]]))
    with pytest.raises(ValueError, match="norm 2"):
        Q.check_unit(np.array([[2.0, 0, 0, 0]]))
    with pytest.raises(ValueError, match=r"\[\.\.\., 4\]"):
        Q.check_unit(np.ones((3, 3)))
    with pytest.raises(ValueError, match="NaN"):
        Q.check_unit(np.array([[np.nan, 0, 0, 1.0]]))


def test_rates_of_a_steady_turn():
    omega = np.array([0.5, -1.0, 2.0])
    t = np.arange(0.0, 1.0, 0.01)
    q = Q.multiply(Q.exp_map(np.array([0.1, 0.2, 0.3])), Q.exp_map(np.outer(t, omega)))
    assert np.allclose(Q.angular_velocity(q, 0.01), omega, atol=1e-9)
    assert np.max(np.abs(Q.angular_acceleration(q, 0.01))) < 1e-6
