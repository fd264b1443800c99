"""The end of the movement (rdmp_gym.dmp.stopping): segmentation, fit, rollout(stop_at), DMPStepper.request_stop."""

import json

import numpy as np
import pytest

from rdmp_gym import RhythmicDMP, load_dmp, save_dmp, wiping_demonstration
from rdmp_gym.dmp.ending import StopRequest, exit_time
from rdmp_gym.dmp.stopping import fit_ending
from rdmp_gym.signals.segmentation import segment_ending
from rdmp_gym.synthetic.demonstrations import ending_demonstration

H = 1e-3                                   # evaluation grid (1 kHz)


def _true_exit(style: int) -> float:
    demo = ending_demonstration(style, rng=0, noise=0.0)
    return demo.truth.transient_length + 3.0 * demo.truth.period


@pytest.fixture(scope="module")
def fitted():
    return {style: fit_ending(ending_demonstration(style, rng=style)) for style in (1, 4)}   # library defaults


@pytest.mark.parametrize("style", [1, 4])
def test_segmentation_finds_the_stop(style):
    demo = ending_demonstration(style, rng=style)
    seg = segment_ending(demo)
    t_exit = _true_exit(style)
    # a smooth departure stays within the noise for a while: the detected end lags a little, never leads
    assert t_exit <= seg.periodic_end <= t_exit + 0.25
    assert t_exit + 1.5 - 0.4 <= seg.rest_time <= t_exit + 1.5
    assert np.linalg.norm(seg.goal - [0.12, -0.10, 0.10]) < 5e-4
    assert abs(seg.start.period - demo.truth.period) < 0.01


def test_segmentation_with_only_two_periods():
    demo = ending_demonstration(3, rng=2, n_periods=2.0, stop_length=0.8)
    seg = segment_ending(demo)
    t_exit = demo.truth.transient_length + 2.0 * demo.truth.period
    assert t_exit <= seg.periodic_end <= t_exit + 0.25
    assert abs(seg.start.period - demo.truth.period) < 0.01


@pytest.mark.parametrize("style", [1, 4])
def test_stop_reproduction_meets_the_bars(fitted, style):
    dmp = fitted[style]
    fine = ending_demonstration(style, rng=0, rate=1000.0, noise=0.0)
    velocity = np.gradient(fine.Y, H, axis=0)
    acceleration = np.gradient(velocity, H, axis=0)
    t_exit = _true_exit(style)
    y, yd = dmp.rollout(fine.t, stop_at=t_exit - 1.0, return_velocity=True)
    a = np.gradient(yd, H, axis=0)
    stop = fine.t >= t_exit
    position = np.max(np.abs(y[stop] - fine.Y[stop]).max(axis=0) / np.ptp(fine.Y, axis=0))
    rel_rmse = np.sqrt(np.mean((a[stop] - acceleration[stop]) ** 2) / np.mean(acceleration[stop] ** 2))
    peak = np.abs(a[stop]).max() / np.abs(acceleration[stop]).max()
    assert position <= 0.01
    assert rel_rmse <= 0.15
    assert peak <= 1.3
    assert np.linalg.norm(y[-1] - fine.Y[-1]) < 1e-3          # at rest within 1 mm of the goal
    assert np.linalg.norm(yd[-1]) < 1e-3                       # and 1 mm/s


def test_request_stop_matches_rollout_and_exits_at_the_demonstrated_phase(fitted):
    dmp = fitted[1]
    dt, request = 2e-3, 4.0
    t = np.arange(0.0, 9.0, dt)
    reference = dmp.rollout(t, stop_at=request)
    stepper = dmp.start(dt)
    path = [stepper.state[0]]
    for i in range(1, t.size):
        if i == round(request / dt):
            when = stepper.request_stop()
        path.append(stepper.step()[0])
    np.testing.assert_allclose(np.array(path), reference, atol=1e-12)
    start = dmp.transients[0]
    phase = start.phi0 + dmp.canonical.omega * when
    assert request <= when < request + dmp.period
    assert abs(np.angle(np.exp(1j * (phase - dmp.ending.exit_phase)))) < 1e-9
    # before the exit nothing changes
    free = dmp.rollout(t)
    before = t < when
    np.testing.assert_allclose(reference[before], free[before], rtol=0, atol=1e-14)
    assert np.abs(reference[~before] - free[~before]).max() > 0.01


def test_a_request_during_the_start_waits_for_the_cycle(fitted):
    dmp = fitted[4]
    t = np.arange(0.0, 11.0, 1e-3)
    y, yd = dmp.rollout(t, stop_at=0.2, return_velocity=True)
    free = dmp.rollout(t)
    start_end = t < dmp.transients[0].length
    np.testing.assert_allclose(y[start_end], free[start_end], atol=1e-12)      # the start is untouched
    peak = np.abs(np.gradient(yd, 1e-3, axis=0)).max()
    assert peak < 1.5 * np.abs(np.gradient(np.gradient(free, 1e-3, axis=0), 1e-3, axis=0)).max()
    assert np.linalg.norm(y[-1] - dmp.ending.goal) < 1e-3


def test_exit_time_is_the_next_crossing():
    omega = 2.0 * np.pi / 1.5
    for request in (0.0, 0.3, 2.9):
        when = exit_time(request, 0.4, omega, 2.0)
        assert request <= when < request + 1.5
        assert abs(np.angle(np.exp(1j * (0.4 + omega * when - 2.0)))) < 1e-9


def test_given_exit_phase_and_goal_come_to_rest(fitted):
    dmp = fitted[1]
    t = np.arange(0.0, 11.0, 1e-3)
    goal = dmp.ending.goal + np.array([0.05, -0.02, 0.03])
    for exit_phase in (dmp.ending.exit_phase + 1.0, dmp.ending.exit_phase + np.pi):
        y, yd = dmp.rollout(t, stop_at=StopRequest(4.0, exit_phase, goal), return_velocity=True)
        assert np.linalg.norm(y[-1] - goal) < 1e-3
        assert np.linalg.norm(yd[-1]) < 1e-3
        assert np.all(np.isfinite(y))
    # anchor, scale and rotation carry the default goal along like the periodic part
    anchor = dmp.anchor + np.array([0.1, 0.05, 0.0])
    y = dmp.rollout(t, anchor=anchor, scale=1.5, rotation=0.4, stop_at=4.0)
    rotation = np.array([[np.cos(0.4), -np.sin(0.4), 0], [np.sin(0.4), np.cos(0.4), 0], [0, 0, 1]])
    expected = anchor + rotation @ (1.5 * (dmp.ending.goal - dmp.anchor))
    assert np.linalg.norm(y[-1] - expected) < 1.5e-3


def test_stop_group_save_load_and_old_files(fitted, tmp_path):
    dmp = fitted[4]
    t = np.arange(0.0, 10.0, 0.01)
    theta = dmp.get_params("stop")
    assert theta.size == dmp.n_dims * dmp.ending.n_basis
    batch = dmp.rollout_batch(np.stack([theta, 1.2 * theta]), t, groups="stop", stop_at=5.0)
    np.testing.assert_allclose(batch[0], dmp.rollout(t, stop_at=5.0), atol=1e-12)
    np.testing.assert_allclose(batch[1], dmp.with_params(1.2 * theta, "stop").rollout(t, stop_at=5.0), atol=1e-12)
    assert np.abs(batch[1] - batch[0]).max() > 1e-3
    assert not np.any(dmp.param_time_weights(t, "stop"))
    weights = dmp.param_time_weights(t, ["periodic", "stop"], stop_at=5.0)             # [T, d (N + S)]
    stop_columns = weights[:, dmp.layout.sizes["periodic"]:]
    exit_at = dmp._stop_plan(StopRequest(5.0), dmp.transients[0], 1.0, dmp.anchor[None],
                             dmp.amplitude[None]).exit_time
    assert not np.any(stop_columns[t < exit_at])
    at_rest = stop_columns[-1].reshape(dmp.n_dims, -1).sum(axis=1)     # the origin's function is 1: sum >= 1 - floor
    assert np.all(at_rest >= 1.0 - dmp.basis.fading.floor) and np.all(at_rest <= 1.0)
    assert np.all(weights <= 1.0 + 1e-12) and np.all(weights >= 0.0)
    path = tmp_path / "ending.json"
    save_dmp(dmp, path)
    back = load_dmp(path)
    np.testing.assert_array_equal(back.rollout(t, stop_at=5.0), dmp.rollout(t, stop_at=5.0))
    data = json.loads(path.read_text())
    del data["stop"]
    path.write_text(json.dumps(data))
    old = load_dmp(path)
    assert old.ending is None
    np.testing.assert_array_equal(old.rollout(t), dmp.rollout(t))


def test_bad_input_is_named(fitted):
    dmp = fitted[1]
    t = np.arange(0.0, 5.0, 0.01)
    plain = RhythmicDMP.fit(wiping_demonstration(1, rng=0))
    with pytest.raises(ValueError, match="stop_at"):
        plain.rollout(t, stop_at=2.0)
    with pytest.raises(ValueError, match="stop_at"):
        plain.start(0.01).request_stop()
    with pytest.raises(ValueError, match="stop_at"):
        dmp.rollout(t, stop_at=-1.0)
    with pytest.raises(TypeError, match="goal"):
        dmp.rollout(t, goal=dmp.ending.goal)                        # the goal belongs to the stop's request
    with pytest.raises(ValueError, match="goal"):
        dmp.rollout(t, stop_at=StopRequest(1.0, goal=[0.0, 0.0]))
    stepper = dmp.start(0.01)
    stepper.request_stop()
    with pytest.raises(ValueError, match="request_stop"):
        stepper.request_stop()
    with pytest.raises(ValueError, match="rest"):
        segment_ending(wiping_demonstration(1, rng=0))
    with pytest.raises(ValueError, match="n_stop"):
        fit_ending(ending_demonstration(1, rng=0), n_stop=1)


def test_stop_with_and_without_the_smooth_start(fitted):
    dmp = fitted[1]
    t = np.arange(0.0, 10.0, 1e-3)
    smooth, smooth_velocity = dmp.rollout(t, stop_at=5.0, return_velocity=True)
    paper, paper_velocity = dmp.rollout(t, stop_at=5.0, start_blend=False, return_velocity=True)
    y0 = dmp.transients[0].start + np.array([0.03, -0.02, 0.01])                  # a start off the demonstrated one
    moved = dmp.rollout(t, y0=y0, stop_at=5.0)
    np.testing.assert_allclose(moved[0], y0, atol=1e-12)
    for y, yd in ((smooth, smooth_velocity), (paper, paper_velocity)):
        assert np.linalg.norm(y[-1] - dmp.ending.goal) < 1e-3 and np.linalg.norm(yd[-1]) < 1e-3
    late = t > 4.0                            # both starts have reached the cycle well before the exit
    np.testing.assert_allclose(paper[late], smooth[late], atol=1e-6)
    np.testing.assert_allclose(moved[late], smooth[late], atol=1e-6)


@pytest.mark.parametrize("field, change", [
    ("fading.nu1", lambda stop: stop["fading"].update(nu1="0.9")),
    ("fading.nu1", lambda stop: stop["fading"].update(nu1=0.1)),                  # below nu2
    ("weights", lambda stop: stop.update(weights=stop["weights"][:2])),
    ("widths", lambda stop: stop["widths"].__setitem__(0, -1.0)),
    ("goal", lambda stop: stop["goal"].__setitem__(1, float("nan"))),
    ("blend_start", lambda stop: stop.update(blend_start=stop["length"])),
    ("stop", lambda stop: stop.update(extra=1)),
    ("length", lambda stop: stop.pop("length")),
])
def test_the_stop_field_is_validated(fitted, field, change):
    from rdmp_gym.dmp.serialization import dmp_from_dict, dmp_to_dict

    data = dmp_to_dict(fitted[1])
    change(data["stop"])
    with pytest.raises(ValueError, match=f"dmp.{field}" if field == "stop" else f"dmp.stop.{field}"):
        dmp_from_dict(data)
