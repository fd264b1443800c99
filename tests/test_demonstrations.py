"""Tests for rdmp_gym.signals.demonstrations: the container, file I/O and the synthetic wiping demos."""

from __future__ import annotations

import numpy as np
import pytest

from rdmp_gym.signals.demonstrations import Demonstration, SyntheticTruth
from rdmp_gym.synthetic.demonstrations import multi_transient_demonstrations, wiping_demonstration

STYLES = (1, 2, 3, 4)


def _index(time: float, dt: float) -> int:
    index = round(time / dt)
    assert abs(index * dt - time) < 1e-9, "the test needs a time on the sampling grid"
    return index


@pytest.mark.parametrize("style", STYLES)
def test_shapes_and_sampling(style: int) -> None:
    demo = wiping_demonstration(style)
    assert demo.Y.shape == (1001, 3) and demo.t.shape == (1001,)
    assert (demo.n_samples, demo.n_dims) == (1001, 3)
    assert demo.dt == pytest.approx(0.01, rel=1e-12)
    assert np.allclose(np.diff(demo.t), 0.01, rtol=1e-9, atol=0.0)
    assert demo.duration == pytest.approx(10.0)
    assert demo.Y.dtype == np.float64 and demo.truth is not None
    assert demo.truth.clean.shape == demo.Y.shape


def test_seeded_determinism() -> None:
    first, again = wiping_demonstration(2, rng=7), wiping_demonstration(2, rng=7)
    other = wiping_demonstration(2, rng=8)
    np.testing.assert_array_equal(first.Y, again.Y)
    assert not np.array_equal(first.Y, other.Y)
    np.testing.assert_array_equal(first.truth.clean, other.truth.clean)
    from_generator = wiping_demonstration(2, rng=np.random.default_rng(7))
    np.testing.assert_array_equal(first.Y, from_generator.Y)
    noise = first.Y - first.truth.clean
    assert np.std(noise) == pytest.approx(3e-4, rel=0.1)
    clean = wiping_demonstration(2, noise=0.0)
    np.testing.assert_array_equal(clean.Y, clean.truth.clean)


@pytest.mark.parametrize("style", STYLES)
def test_clean_signal_is_composed_periodic(style: int) -> None:
    demo = wiping_demonstration(style)
    truth = demo.truth
    step = _index(truth.period, demo.dt)
    start = _index(truth.transient_length, demo.dt)
    mismatch = np.abs(truth.clean[step:] - truth.clean[:-step]).max(axis=1)
    assert mismatch[start:].max() < 1e-12  # periodic from T on ...
    assert mismatch[:start].min() > 1e-12  # ... and from no earlier sample
    assert mismatch[:100].min() > 0.01  # the first second is far from periodic
    assert np.all(truth.clean[start:, 2] == 0.0)  # on the table during the periodic part
    assert truth.clean[:, 2].min() > -1e-12  # never below it
    one_period = truth.clean[start:start + step]
    np.testing.assert_allclose(one_period.mean(axis=0), truth.anchor, atol=1e-12)
    np.testing.assert_allclose(truth.clean[0], [-0.15, 0.20, 0.12], atol=1e-12)
    assert np.abs(truth.clean[1] - truth.clean[0]).max() / demo.dt < 1e-5  # starts at rest


@pytest.mark.parametrize("style", STYLES)
def test_smooth_at_the_transient_length(style: int) -> None:
    """Finite-difference 2nd and 3rd derivatives (at 1 kHz) jump no more at T than near it."""
    demo = wiping_demonstration(style, rate=1000.0)
    clean, dt = demo.truth.clean, demo.dt
    start = _index(demo.truth.transient_length, dt)
    for order in (2, 3):
        derivative = np.diff(clean, order, axis=0) / dt**order
        jumps = np.abs(np.diff(derivative, axis=0)).max(axis=1)
        near = jumps[start - order - 3:start + 3].max()
        elsewhere = max(jumps[start - 30:start - 10].max(), jumps[start + 10:start + 30].max())
        assert near <= 1.5 * elsewhere, (order, near, elsewhere)


@pytest.mark.parametrize("style", STYLES)
def test_pattern_sizes(style: int) -> None:
    demo = wiping_demonstration(style)
    start = _index(demo.truth.transient_length, demo.dt)
    periodic = demo.truth.clean[start:, :2]
    extent = np.ptp(periodic, axis=0)
    if style in (1, 2):
        np.testing.assert_allclose(np.linalg.norm(periodic, axis=1), 0.05, atol=1e-12)
    else:
        np.testing.assert_allclose(extent, [0.12, 0.06], atol=2e-3)
    assert 1.4 <= demo.truth.period <= 1.7


def _straightness_gap(demo: Demonstration) -> float:
    """Largest distance (m) of the approach from the straight segment start -> y(T)."""
    start = _index(demo.truth.transient_length, demo.dt)
    path = demo.truth.clean[:start + 1]
    chord = path[-1] - path[0]
    along = np.clip((path - path[0]) @ chord / (chord @ chord), 0.0, 1.0)
    return float(np.linalg.norm(path - path[0] - along[:, None] * chord, axis=1).max())


def test_complex_approach_is_not_straight() -> None:
    for simple, complex_ in ((1, 2), (3, 4)):
        simple_demo, complex_demo = wiping_demonstration(simple), wiping_demonstration(complex_)
        assert _straightness_gap(complex_demo) > _straightness_gap(simple_demo) + 0.03
        height_simple, height_complex = simple_demo.truth.clean[:, 2], complex_demo.truth.clean[:, 2]
        assert np.all(np.diff(height_simple) <= 1e-12)  # a simple approach only descends
        assert height_complex.max() > height_complex[0] + 0.01  # a complex one lifts first


def test_options_are_honoured() -> None:
    demo = wiping_demonstration(1, duration=6.0, rate=50.0, start=(0.1, 0.1, 0.2),
                                anchor=(0.3, -0.1, 0.05), period=1.2, transient_length=1.6)
    truth = demo.truth
    assert demo.Y.shape == (301, 3) and demo.dt == pytest.approx(0.02)
    assert (truth.period, truth.transient_length) == (1.2, 1.6)
    np.testing.assert_array_equal(truth.anchor, [0.3, -0.1, 0.05])
    np.testing.assert_allclose(truth.clean[0], [0.1, 0.1, 0.2], atol=1e-12)
    assert np.all(truth.clean[_index(1.6, demo.dt):, 2] == 0.05)


def test_multi_transient_demonstrations_share_one_pattern() -> None:
    demos = multi_transient_demonstrations(3, rng=3)
    truths = [demo.truth for demo in demos]
    period = truths[0].period
    assert all(truth.period == period for truth in truths)
    lengths = [truth.transient_length for truth in truths]
    entrances = [truth.entrance_time for truth in truths]
    assert len(set(lengths)) == 3 and len(set(entrances)) == 3
    np.testing.assert_allclose(entrances, [0.0, period / 3, 2 * period / 3])
    starts = np.array([truth.clean[0] for truth in truths])
    assert np.min(np.linalg.norm(starts[:, None] - starts[None], axis=2) + np.eye(3)) > 0.1
    dt = demos[0].dt
    reference = truths[0].clean[_index(lengths[0], dt):]
    for truth in truths[1:]:
        own = truth.clean[_index(truth.transient_length, dt):]
        lag = _index(truth.entrance_time - truths[0].entrance_time, dt)
        n = min(own.size, reference.size) // 3 - lag
        np.testing.assert_allclose(own[:n], reference[lag:lag + n], atol=1e-12)
    assert not np.array_equal(demos[0].Y - truths[0].clean, demos[1].Y - truths[1].clean)
    again = multi_transient_demonstrations(3, rng=3)
    for first, second in zip(demos, again, strict=True):
        np.testing.assert_array_equal(first.Y, second.Y)


def test_one_dimensional_input_becomes_a_column() -> None:
    demo = Demonstration(t=np.arange(5) * 0.1, Y=np.arange(5.0))
    assert demo.Y.shape == (5, 1) and demo.n_dims == 1


def test_arrays_are_read_only_copies() -> None:
    t, Y = np.arange(4) * 0.5, np.zeros((4, 2))
    demo = Demonstration(t=t, Y=Y)
    Y[0, 0] = 1.0
    assert demo.Y[0, 0] == 0.0
    with pytest.raises(ValueError):
        demo.Y[0, 0] = 2.0
    with pytest.raises(ValueError):
        demo.t[0] = 2.0


def test_csv_round_trip_is_lossless(tmp_path) -> None:
    demo = wiping_demonstration(3, rng=1)
    path = tmp_path / "demo.csv"
    demo.to_csv(path)
    assert path.read_text().splitlines()[0] == "t,y0,y1,y2"
    loaded = Demonstration.from_csv(path)
    np.testing.assert_array_equal(loaded.t, demo.t)
    np.testing.assert_array_equal(loaded.Y, demo.Y)
    assert loaded.name == "demo"
    demo.to_csv(path, columns=["x", "y", "z"], time_column="time")
    assert path.read_text().splitlines()[0] == "time,x,y,z"
    np.testing.assert_array_equal(Demonstration.from_csv(path, time_column="time").Y, demo.Y)


def test_csv_time_column_anywhere(tmp_path) -> None:
    path = tmp_path / "columns.csv"
    path.write_text("a,time,b\n1.0,0.0,5.0\n2.0,0.5,6.0\n3.0,1.0,7.0\n")
    demo = Demonstration.from_csv(path, time_column="time")
    np.testing.assert_array_equal(demo.t, [0.0, 0.5, 1.0])
    np.testing.assert_array_equal(demo.Y, [[1.0, 5.0], [2.0, 6.0], [3.0, 7.0]])
    with pytest.raises(ValueError, match="time_column"):
        Demonstration.from_csv(path)


def test_npz_round_trip_is_lossless(tmp_path) -> None:
    demo = wiping_demonstration(4, rng=2)
    path = tmp_path / "demo.npz"
    demo.to_npz(path)
    loaded = Demonstration.from_npz(path)
    np.testing.assert_array_equal(loaded.t, demo.t)
    np.testing.assert_array_equal(loaded.Y, demo.Y)
    assert loaded.name == demo.name
    np.savez(tmp_path / "partial.npz", t=demo.t)
    with pytest.raises(ValueError, match=r"path: .*\['Y'\]"):
        Demonstration.from_npz(tmp_path / "partial.npz")


def _grid(n: int = 6) -> tuple[np.ndarray, np.ndarray]:
    return np.arange(n) * 0.01, np.zeros((n, 2))


@pytest.mark.parametrize(("change", "name"), [
    ("nan_y", "Y"), ("inf_t", "t"), ("non_increasing", "t"), ("uneven", "t"),
    ("short_y", "Y"), ("rank_3", "Y"), ("no_columns", "Y"),
])
def test_bad_demonstrations_raise_naming_the_argument(change: str, name: str) -> None:
    t, Y = _grid()
    if change == "nan_y":
        Y[2, 1] = np.nan
    elif change == "inf_t":
        t[3] = np.inf
    elif change == "non_increasing":
        t[3] = t[2]
    elif change == "uneven":
        t[3] += 0.004
    elif change == "short_y":
        Y = Y[:-1]
    elif change == "rank_3":
        Y = Y[:, :, None]
    else:
        Y = Y[:, :0]
    with pytest.raises(ValueError, match=rf"^{name}:"):
        Demonstration(t=t, Y=Y)


def test_bad_types_raise_type_error() -> None:
    t, Y = _grid()
    with pytest.raises(TypeError, match="name"):
        Demonstration(t=t, Y=Y, name=3)
    with pytest.raises(TypeError, match="truth"):
        Demonstration(t=t, Y=Y, truth="clean")
    with pytest.raises(TypeError, match="rng"):
        wiping_demonstration(1, rng="seed")


@pytest.mark.parametrize(("kwargs", "name"), [
    ({"style": 0}, "style"), ({"style": 5}, "style"), ({"style": 1.5}, "style"),
    ({"style": True}, "style"), ({"noise": -1.0}, "noise"), ({"noise": np.nan}, "noise"),
    ({"duration": 0.0}, "duration"), ({"duration": 1.0}, "duration"), ({"rate": -5.0}, "rate"),
    ({"period": 0.0}, "period"), ({"transient_length": np.inf}, "transient_length"),
    ({"start": (0.0, 1.0)}, "start"), ({"anchor": (0.0, np.nan, 0.0)}, "anchor"),
])
def test_bad_generator_arguments(kwargs: dict, name: str) -> None:
    with pytest.raises(ValueError, match=rf"^{name}:"):
        wiping_demonstration(**kwargs)


@pytest.mark.parametrize(("kwargs", "name"), [
    ({"n": 0}, "n"), ({"transient_lengths": [1.0, 2.0]}, "transient_lengths"),
    ({"transient_lengths": [1.0, 2.0, 20.0]}, "transient_lengths"),
    ({"entrance_times": [0.0, np.inf, 1.0]}, "entrance_times"),
    ({"starts": np.zeros((3, 2))}, "starts"),
])
def test_bad_multi_arguments(kwargs: dict, name: str) -> None:
    with pytest.raises(ValueError, match=rf"^{name}:"):
        multi_transient_demonstrations(**kwargs)


def test_bad_truth() -> None:
    clean = np.zeros((4, 3))
    with pytest.raises(ValueError, match="entrance_time"):
        SyntheticTruth(period=1.0, transient_length=0.5, anchor=np.zeros(3), clean=clean,
                       entrance_time=1.0)
    with pytest.raises(ValueError, match="clean"):
        SyntheticTruth(period=1.0, transient_length=0.5, anchor=np.zeros(2), clean=clean)
    truth = SyntheticTruth(period=1.0, transient_length=0.5, anchor=np.zeros(3), clean=clean)
    with pytest.raises(ValueError, match="truth"):
        Demonstration(t=np.arange(5) * 0.1, Y=np.zeros((5, 3)), truth=truth)
