"""The batched transformation system: in-place and position-only variants give the same numbers."""

import numpy as np

from rdmp_gym.dmp.transformation import TransformationSystem


def _system_and_input():
    system = TransformationSystem(2 * np.pi / 1.5, 0.01, 5.0)
    rng = np.random.default_rng(0)
    forcing, anchor = rng.normal(size=(4, 300, 3)), rng.normal(size=(4, 3))
    return system, forcing, anchor, rng.normal(size=(4, 3)), rng.normal(size=(4, 3))


def test_positions_only_are_the_positions_of_the_full_rollout():
    system, forcing, anchor, y0, z0 = _system_and_input()
    y, z = system.rollout(system.input(anchor, forcing), y0, z0)
    y_only, none = system.rollout(system.input(anchor, forcing), y0, z0, velocity=False)
    assert none is None and z.shape == y.shape
    np.testing.assert_array_equal(y_only, y)


def test_input_in_place_equals_input():
    system, forcing, anchor, *_ = _system_and_input()
    expected = system.input(anchor, forcing)
    moving = anchor[:, None, :] + np.linspace(0, 1, forcing.shape[1])[None, :, None]
    expected_moving = system.input(moving, forcing)
    copy = forcing.copy()
    assert system.input(anchor, copy, out=copy) is copy
    np.testing.assert_array_equal(copy, expected)
    copy = forcing.copy()
    np.testing.assert_array_equal(system.input(moving, copy, out=copy), expected_moving)
    assert not np.array_equal(expected, expected_moving)
    scratch, kept = moving.copy(), anchor.copy()                  # a moving anchor may be overwritten, a constant not
    np.testing.assert_array_equal(system.input(scratch, forcing.copy(), scratch=True), expected_moving)
    np.testing.assert_array_equal(system.input(kept, forcing.copy(), scratch=True), expected)
    assert not np.array_equal(scratch, moving) and np.array_equal(kept, anchor)


def test_more_initial_states_than_inputs_broadcast():
    system, forcing, anchor, y0, z0 = _system_and_input()
    u = system.input(anchor[0], forcing[0])                          # one input [T, d], four initial states
    y, z = system.rollout(u, y0, z0)
    assert y.shape == z.shape == (4, *u.shape)
    for row in range(4):
        y_row, z_row = system.rollout(u, y0[row], z0[row])
        np.testing.assert_array_equal(y[row], y_row)
        np.testing.assert_array_equal(z[row], z_row)
