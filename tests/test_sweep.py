"""The anchor's travel (Sweep): the minimum-jerk path itself, and a DMP whose pattern runs on it."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rdmp_gym import RhythmicDMP, Sweep, load_dmp, save_dmp
from rdmp_gym.dmp.ending import StopRequest
from rdmp_gym.dmp.serialization import dmp_from_dict, dmp_to_dict

T_FINE = np.linspace(0.0, 6.0, 6001)


def _sweep(points=None):
    times = np.array([1.0, 2.0, 3.0, 4.5])
    points = np.array([[0.05, 0.0, 0.0], [0.0, 0.04, 0.0], [-0.03, -0.02, 0.0]]) if points is None else points
    return Sweep(times, points)


def test_path_rests_then_passes_the_via_points_then_rests():
    sweep = _sweep()
    offsets = sweep.offsets(T_FINE)
    assert np.all(offsets[T_FINE <= 1.0] == 0.0)
    for time, point in zip(sweep.times[1:], sweep.points, strict=True):
        np.testing.assert_allclose(sweep.offsets(np.array([time]))[0], point, atol=1e-12)
    np.testing.assert_allclose(offsets[T_FINE >= 4.5], np.broadcast_to(sweep.points[-1], offsets[T_FINE >= 4.5].shape),
                               atol=1e-12)
    for derivative in (1, 2):    # leaves and reaches its rest with zero velocity and acceleration
        rates = sweep.offsets(sweep.times[[0, -1]], derivative=derivative)
        np.testing.assert_allclose(rates, 0.0, atol=1e-9)


def test_path_is_c2_everywhere():
    sweep = _sweep()
    dt = T_FINE[1] - T_FINE[0]
    acceleration = sweep.offsets(T_FINE, derivative=2)
    jerk = np.diff(acceleration, axis=0) / dt        # finite: no jump in the acceleration anywhere
    assert np.max(np.abs(np.diff(acceleration, axis=0))) < 1e-2 * np.max(np.abs(acceleration))
    np.testing.assert_allclose(np.diff(sweep.offsets(T_FINE), axis=0) / dt, sweep.offsets(T_FINE, derivative=1)[1:],
                               atol=2e-3 * np.max(np.abs(sweep.offsets(T_FINE, derivative=1))))
    assert np.all(np.isfinite(jerk))


def test_one_via_point_is_the_minimum_jerk_profile():
    sweep = Sweep(np.array([0.5, 2.5]), np.array([[0.1, -0.2]]))
    s = np.linspace(0.0, 1.0, 101)
    profile = 10 * s**3 - 15 * s**4 + 6 * s**5
    np.testing.assert_allclose(sweep.offsets(0.5 + 2.0 * s), profile[:, None] * sweep.points, atol=1e-12)


@settings(max_examples=25, deadline=None)
@given(st.lists(st.floats(-0.2, 0.2), min_size=9, max_size=9))
def test_offsets_are_linear_in_the_points(values):
    sweep = _sweep()
    batch = np.stack([sweep.points, np.reshape(values, (3, 3))])
    together = sweep.offsets(T_FINE[::10], batch)
    for row, points in zip(together, batch, strict=True):
        np.testing.assert_allclose(row, sweep.basis(T_FINE[::10]) @ points, atol=1e-14)
    np.testing.assert_allclose(together[0], sweep.offsets(T_FINE[::10]), atol=1e-14)


@pytest.mark.parametrize(("times", "points", "message"), [
    (np.array([1.0]), np.zeros((0, 2)), "times"),
    (np.array([1.0, 1.0]), np.zeros((1, 2)), "times"),
    (np.array([-1.0, 1.0]), np.zeros((1, 2)), "times"),
    (np.array([0.0, 1.0, 2.0]), np.zeros((1, 2)), "points"),
    (np.array([0.0, np.nan]), np.zeros((1, 2)), "times"),
    (np.array([0.0, 1.0]), np.array([[np.inf, 0.0]]), "points"),
])
def test_bad_sweeps_are_refused_by_name(times, points, message):
    with pytest.raises(ValueError, match=message):
        Sweep(times, points)


def test_uniform_and_its_checks():
    sweep = Sweep.uniform(1.0, 5.0, 4, 3)
    np.testing.assert_allclose(sweep.times, [1.0, 2.0, 3.0, 4.0, 5.0])
    assert sweep.points.shape == (4, 3) and not sweep.points.any()
    with pytest.raises(ValueError, match="n_points"):
        Sweep.uniform(1.0, 5.0, 0, 3)
    with pytest.raises(ValueError, match="start, end"):
        Sweep.uniform(5.0, 1.0, 2, 3)


# ---------------------------------------------------------------------------------------------------- in a DMP
@pytest.fixture(scope="module")
def travelling(dmp):
    return dmp.with_sweep(_sweep())


def test_a_sweep_at_rest_changes_nothing(dmp):
    t = np.arange(0.0, 6.0, 0.002)
    still = dmp.with_sweep(Sweep(np.array([1.0, 2.0, 3.0, 4.5]), np.zeros((3, 3))))
    np.testing.assert_allclose(still.rollout(t), dmp.rollout(t), atol=1e-12)


@pytest.mark.parametrize("tempo", [1.0, 2.0, 0.7])
def test_the_pattern_is_carried_rigidly_along_the_path(dmp, travelling, tempo):
    """With the sweep, the rollout is the rollout without it moved by the sweep's offset, at every sample and at
    any tempo (the travel runs in unit-tempo time): no lag, no overshoot, velocity and acceleration included."""
    t = np.arange(0.0, 8.0, 0.001)
    (y, yd), (y_still, yd_still) = (d.rollout(t, tempo=tempo, return_velocity=True) for d in (travelling, dmp))
    tau = t * tempo
    path = travelling.sweep.offsets(tau)
    assert np.max(np.abs(y - y_still - path)) < 1e-5 * np.max(np.abs(path))
    np.testing.assert_allclose(yd - yd_still, tempo * travelling.sweep.offsets(tau, derivative=1), atol=1e-4)


def test_parameters_batch_and_stepper_agree(dmp, travelling):
    t = np.arange(0.0, 5.0, 0.004)
    slices = travelling.param_slices()
    assert list(slices)[-1] == "sweep" and travelling.layout.size("sweep") == 9
    theta = travelling.get_params()
    np.testing.assert_array_equal(theta[slices["sweep"]], travelling.sweep.points.ravel())
    other = travelling.sweep.points[::-1].ravel()
    batch = travelling.rollout_batch(np.stack([travelling.get_params("sweep"), other]), t, groups="sweep")
    np.testing.assert_allclose(batch[0], travelling.rollout(t), atol=1e-12)
    np.testing.assert_allclose(batch[1], travelling.with_params(other, "sweep").rollout(t), atol=1e-12)
    stepper = travelling.start(t[1] - t[0])
    steps = np.array([stepper.step()[0] for _ in range(t.size - 1)])
    np.testing.assert_allclose(steps, batch[0][1:], atol=1e-9)
    assert "sweep" not in dmp.layout.sizes
    with pytest.raises(ValueError, match="sweep"):
        dmp.get_params("sweep")


def test_file_keeps_the_sweep(tmp_path, travelling):
    save_dmp(travelling, tmp_path / "dmp.json")
    loaded = load_dmp(tmp_path / "dmp.json")
    np.testing.assert_array_equal(loaded.sweep.times, travelling.sweep.times)
    np.testing.assert_array_equal(loaded.sweep.points, travelling.sweep.points)
    data = dmp_to_dict(travelling)
    data["sweep"]["points"] = data["sweep"]["points"][:-1]
    with pytest.raises(ValueError, match=r"dmp\.sweep\.points"):
        dmp_from_dict(data)
    data["sweep"] = {"times": [2.0, 1.0], "points": [[0.0, 0.0, 0.0]]}
    with pytest.raises(ValueError, match=r"dmp\.sweep\.times"):
        dmp_from_dict(data)


def test_sweep_dimensions_must_match(dmp):
    with pytest.raises(ValueError, match="sweep"):
        dmp.with_sweep(Sweep(np.array([0.0, 1.0]), np.zeros((1, 2))))
    with pytest.raises(ValueError, match="sweep"):
        RhythmicDMP(dmp.canonical, dmp.basis, dmp.weights, dmp.transients, dmp.anchor, sweep="along x")


def test_a_stop_after_the_travel_comes_to_rest_at_its_goal():
    from rdmp_gym.dmp.stopping import fit_ending
    from rdmp_gym.synthetic.demonstrations import ending_demonstration

    dmp = fit_ending(ending_demonstration(1, rng=1))
    travelling = dmp.with_sweep(Sweep(np.array([1.0, 2.5, 4.0]), np.array([[0.06, 0.0, 0.0], [0.06, 0.05, 0.0]])))
    dt, request = 2e-3, 5.0
    t = np.arange(0.0, 11.0, dt)
    goal = dmp.ending.goal + np.array([0.08, 0.05, 0.0])
    y = travelling.rollout(t, stop_at=StopRequest(request, goal=goal))
    assert np.linalg.norm(y[-1] - goal) < 1e-3
    stepper = travelling.start(dt)
    path = [stepper.state[0]]
    for i in range(1, t.size):
        if i == round(request / dt):
            stepper.request_stop(goal=goal)
        path.append(stepper.step()[0])
    np.testing.assert_allclose(np.array(path), y, atol=1e-9)
