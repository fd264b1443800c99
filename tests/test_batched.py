"""Batched rollouts with perturbed initial conditions: every rollout on its own canonical path, the same
numbers as one rollout at a time."""

from dataclasses import replace

import numpy as np
import pytest

from rdmp_gym import RhythmicDMP, wiping_demonstration
from rdmp_gym.dmp.basis import NORMALISATION_EPSILON
from rdmp_gym.dmp.batched import batched_forcing


@pytest.fixture(scope="module")
def dmp():
    return RhythmicDMP.fit(wiping_demonstration(3, rng=0), 40, 40)


@pytest.fixture(scope="module")
def thetas(dmp):
    groups = ("periodic", "transient", "initial", "amplitude")
    theta = dmp.get_params(groups)
    rng = np.random.default_rng(1)
    batch = theta + np.concatenate([rng.normal(0, 5.0, (8, theta.size - 5)),
                                    rng.normal(0, [0.3, 0.3 * theta[-4]], (8, 2)),
                                    rng.normal(0, 0.1, (8, 3))], axis=1)
    batch[:2, -5:-3] = theta[-5:-3]             # two rollouts share the fitted canonical path
    return groups, batch


@pytest.mark.parametrize("floor", [None, NORMALISATION_EPSILON])     # the fit's floor and the bare mixture's
@pytest.mark.parametrize("samples", [1000, 1])                          # one rollout per block, all in one block
def test_batched_forcing_equals_the_forcing_of_each_path(dmp, thetas, floor, samples):
    groups, batch = thetas
    weights, inits, *_ = dmp._decode(batch, groups)
    basis = dmp.basis if floor is None else replace(dmp.basis, fading=replace(dmp.basis.fading, floor=floor))
    t = np.arange(samples) * 0.01
    phi, r = dmp.canonical.state(t, inits[:, 0, 0], inits[:, 0, 1])
    forcing = batched_forcing(basis, phi, r, weights)
    assert forcing.shape == (len(batch), samples, dmp.n_dims)
    for b in range(len(batch)):     # round-off (1.4e-14 measured); the periodic terms left out move it by < 1e-17
        single = basis.forcing(phi[b], r[b], weights[b])
        np.testing.assert_allclose(forcing[b], single, rtol=0, atol=1e-12 * np.abs(single).max())
    assert np.all(np.isfinite(forcing))


def test_perturbed_initial_conditions_roll_out_like_single_rollouts(dmp, thetas):
    groups, batch = thetas
    t = np.arange(1000) * 0.01
    rollouts = dmp.rollout_batch(batch, t, groups)
    assert rollouts.shape == (len(batch), t.size, dmp.n_dims)
    size = np.ptp(rollouts, axis=1).max()
    for b, theta in enumerate(batch):
        single = dmp.with_params(theta, groups).rollout(t)
        np.testing.assert_allclose(rollouts[b], single, rtol=0, atol=1e-13 * size)     # 3e-15 measured
    # the perturbed starts differ from one another: every rollout really had its own path
    assert np.ptp(rollouts[2:, :100], axis=0).max() > 1e-3 * size


def test_batched_forcing_rejects_mismatched_shapes(dmp):
    phi = np.zeros((2, 10))
    with pytest.raises(ValueError, match="phi, r"):
        batched_forcing(dmp.basis, phi, np.ones((2, 11)), np.zeros((2, 3, dmp.basis.n_basis)))
    with pytest.raises(ValueError, match="weights"):
        batched_forcing(dmp.basis, phi, np.ones((2, 10)), np.zeros((3, 3, dmp.basis.n_basis)))


def test_batched_forcing_where_a_gate_is_exactly_zero(dmp):
    """Paths from inside the cycle start where the transient gate is floored to 0, paths from far outside where the
    periodic one is: the skipped spans are exactly 0, as in ``BasisSet.activations``."""
    t = np.arange(600) * 0.01
    r0 = np.array([0.15, 0.3, 1.0, 3.0, 40.0])
    phi, r = dmp.canonical.state(t, np.linspace(0.0, 2.0, r0.size), r0)
    weights = np.random.default_rng(2).normal(0, 5.0, (r0.size, dmp.n_dims, dmp.basis.n_basis))
    raw = [dmp.basis.activations(phi[b], r[b]) for b in range(r0.size)]
    n = dmp.basis.n_periodic
    assert np.any(raw[0][:, n:].sum(axis=1) == 0.0) and np.any(raw[-1][:, :n].sum(axis=1) == 0.0)
    forcing = batched_forcing(dmp.basis, phi, r, weights)
    for b in range(r0.size):
        single = dmp.basis.forcing(phi[b], r[b], weights[b])
        np.testing.assert_allclose(forcing[b], single, rtol=0, atol=1e-12 * np.abs(single).max())
