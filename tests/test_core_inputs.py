"""Core gaps of issue 11 (item 10): every bad input is a clear error, long rollouts run in bounded memory."""

import codecs
import tracemalloc

import numpy as np
import pytest

from rdmp_gym import PeriodicDMP, RhythmicDMP, wiping_demonstration
from rdmp_gym.signals.demonstrations import Demonstration


@pytest.fixture(scope="module")
def periodic(demo):
    return PeriodicDMP.fit(demo, n_periodic=10)


@pytest.mark.parametrize("fit", [RhythmicDMP.fit, PeriodicDMP.fit])
@pytest.mark.parametrize(("keyword", "value", "error", "message"), [
    ("regularization", -1.0, ValueError, "regularization"),
    ("regularization", float("nan"), ValueError, "regularization"),
    ("n_periodic", 2.7, TypeError, "n_periodic"),
    ("n_periodic", True, TypeError, "n_periodic"),
    ("smoothing", float("nan"), ValueError, "smoothing"),
    ("smoothing", 0.0, ValueError, "smoothing"),
    ("smoothing", -0.1, ValueError, "smoothing"),
])
def test_fit_keywords_are_checked(demo, fit, keyword, value, error, message):
    with pytest.raises(error, match=message):
        fit(demo, **{keyword: value})


def test_n_transient_must_be_an_integer(demo):
    with pytest.raises(TypeError, match="n_transient"):
        RhythmicDMP.fit(demo, n_transient=3.5)


@pytest.mark.parametrize(("argument", "value", "message"), [
    ("weights", np.full((3, 10), np.nan), "weights"),
    ("anchor", np.array([0.0, np.nan, 0.0]), "anchor"),
    ("anchor", np.zeros(2), r"anchor: expected shape \(3,\)"),
    ("phi0", float("inf"), "phi0"),
    ("start", np.zeros(4), "start"),
    ("start_velocity", [np.nan, 0.0, 0.0], "start_velocity"),
])
def test_periodic_dmp_checks_its_inputs(periodic, argument, value, message):
    arguments = {"period": periodic.period, "weights": periodic.weights, "anchor": periodic.anchor,
                 "phi0": periodic.phi0, "start": periodic.start, "start_velocity": periodic.start_velocity}
    arguments[argument] = value
    with pytest.raises(ValueError, match=message):
        PeriodicDMP(**arguments)


def test_periodic_dmp_rollout_checks_its_inputs(periodic):
    t = np.linspace(0.0, 2.0, 201)
    for name, value in (("y0", [np.nan, 0.0, 0.0]), ("yd0", np.zeros(2)), ("anchor", [0.0, 0.0, np.inf])):
        with pytest.raises(ValueError, match=name):
            periodic.rollout(t, **{name: value})
    assert np.all(np.isfinite(periodic.rollout(t)))


def test_rollout_batch_of_zero_parameter_sets_is_a_clear_error(dmp):
    with pytest.raises(ValueError, match=r"thetas: expected at least one"):
        dmp.rollout_batch(np.zeros((0, dmp.layout.size(None))), np.linspace(0.0, 1.0, 11))


def _peak_bytes(function):
    tracemalloc.start()
    try:
        result = function()
        return tracemalloc.get_traced_memory()[1], result
    finally:
        tracemalloc.stop()


def test_long_rollouts_grow_in_memory_like_their_output_only():
    dmp = RhythmicDMP.fit(wiping_demonstration(1, rng=0), n_periodic=40, n_transient=40)   # D = 80
    short, long = np.arange(0.0, 50.0, 1e-3), np.arange(0.0, 200.0, 1e-3)    # 50 s and 200 s at 1 kHz
    peak_short, y_short = _peak_bytes(lambda: dmp.rollout(short))
    peak_long, y_long = _peak_bytes(lambda: dmp.rollout(long))
    growth, output_growth = peak_long - peak_short, y_long.nbytes - y_short.nbytes
    # unblocked, the [T, D] activations add about 70 output sizes (measured); in blocks about 9 remain,
    # the O(T d) arrays of the integration
    assert growth < 15 * output_growth, (growth / 1e6, output_growth / 1e6)
    np.testing.assert_allclose(y_long[: short.size], y_short, rtol=0, atol=1e-12)


def _write_csv(path, text, encoding):
    path.write_bytes(codecs.BOM_UTF8 + text.encode() if encoding == "utf-8-sig" else text.encode(encoding))


@pytest.mark.parametrize("encoding", ["utf-8", "utf-8-sig", "utf-16", "utf-16-le-bom", "utf-16-be-bom"])
def test_csv_in_the_encodings_spreadsheets_write_is_read(tmp_path, encoding):
    demo = wiping_demonstration(2, rng=0)
    demo.to_csv(tmp_path / "plain.csv")
    text = (tmp_path / "plain.csv").read_text()
    path = tmp_path / "demo.csv"
    if encoding.endswith("-bom"):
        bom = codecs.BOM_UTF16_LE if "-le-" in encoding else codecs.BOM_UTF16_BE
        path.write_bytes(bom + text.encode("utf-16-le" if "-le-" in encoding else "utf-16-be"))
    else:
        _write_csv(path, text, encoding)
    loaded = Demonstration.from_csv(path)
    np.testing.assert_array_equal(loaded.Y, demo.Y)
    np.testing.assert_array_equal(loaded.t, demo.t)


def test_csv_that_is_not_text_or_repeats_a_column_is_a_clear_error(tmp_path):
    path = tmp_path / "demo.csv"
    path.write_bytes(b"t,y0\n0,\xff\xfe\xfd\n")
    with pytest.raises(ValueError, match="UTF-8 or UTF-16"):
        Demonstration.from_csv(path)
    path.write_text("t,y0,y0,t\n0,1,2,0\n0.1,1,2,0.1\n")
    with pytest.raises(ValueError, match=r"\['t', 'y0'\] more than once"):
        Demonstration.from_csv(path)


def test_broken_npz_files_are_clear_errors(tmp_path):
    demo = wiping_demonstration(2, rng=0)
    demo.to_npz(tmp_path / "demo.npz")
    whole = (tmp_path / "demo.npz").read_bytes()
    (tmp_path / "cut.npz").write_bytes(whole[: len(whole) // 2])
    with pytest.raises(ValueError, match=r"cut.npz"):
        Demonstration.from_npz(tmp_path / "cut.npz")
    np.save(tmp_path / "array.npy", demo.Y)
    with pytest.raises(ValueError, match=r"single .npy array"):
        Demonstration.from_npz(tmp_path / "array.npy")
    (tmp_path / "empty.npz").write_bytes(b"")
    with pytest.raises(ValueError, match=r"empty.npz"):
        Demonstration.from_npz(tmp_path / "empty.npz")


def test_a_control_rate_above_the_physics_rate_is_refused():
    gym = pytest.importorskip("gymnasium")
    import rdmp_gym.envs  # noqa: F401

    with pytest.raises(ValueError, match=r"control_rate: expected at most the physics rate 500 Hz"):
        gym.make("rdmp_gym/ArmarWipe-v1", disable_env_checker=True, control_rate=1e6, n_periodic=10, n_transient=10)
