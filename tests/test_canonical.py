"""Properties of the canonical system (3) and init_T."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rdmp_gym import CanonicalSystem


def reference_radius(cs: CanonicalSystem, t: np.ndarray, r0: float) -> np.ndarray:
    sol = solve_ivp(lambda _, r: cs.radial_rate(r), (t[0], t[-1]), [r0], t_eval=t, method="DOP853",
                    rtol=1e-13, atol=1e-14)
    return sol.y[0]


@pytest.mark.parametrize("r0", [0.05, 0.7, 0.999, 1.001, 1.5, 8.5, 41.0])
def test_radius_matches_fine_reference(r0):
    cs = CanonicalSystem(period=1.5)
    t = np.linspace(0.0, 6.0, 601)
    assert np.max(np.abs(cs.radius(t, r0) - reference_radius(cs, t, r0))) < 1e-8


@pytest.mark.parametrize("r0", [0.2, 0.9, 1.1, 30.0])
def test_radius_converges_to_mu_monotonically(r0):
    cs = CanonicalSystem(period=1.0, mu=1.3)
    r = cs.radius(np.linspace(0.0, 20.0, 2001), r0)
    assert abs(r[-1] - 1.3) < 1e-9
    steps = np.diff(r)
    assert np.all(steps <= 0) if r0 > 1.3 else np.all(steps >= 0)
    assert np.all((r - 1.3) * (r0 - 1.3) >= 0)          # never crosses the limit cycle


def test_paths_never_cross():
    cs = CanonicalSystem(period=1.0)
    r = cs.radius(np.linspace(0.0, 5.0, 501), np.array([0.3, 0.8, 1.2, 4.0, 40.0]))
    assert np.all(np.diff(r, axis=0) > 0)                 # ordering of radii is preserved at every time


def test_batched_radius_equals_single():
    cs = CanonicalSystem(period=2.0)
    t = np.linspace(0.0, 3.0, 301)
    r0 = np.array([0.5, 2.0, 9.0])
    batched = cs.radius(t, r0)
    for row, start in zip(batched, r0, strict=True):
        np.testing.assert_array_equal(row, cs.radius(t, start))


def test_radius_of_many_paths_in_blocks_equals_one_path_at_a_time():
    """Many paths (several blocks of samples): paths below, on and above the cycle, one branch per block or mixed."""
    cs = CanonicalSystem(period=1.5)
    t = np.linspace(0.0, 10.0, 1001)
    r0 = np.r_[np.linspace(1.5, 30.0, 20), np.linspace(0.2, 0.9, 9), 1.0, np.linspace(2.0, 3.0, 10)]
    batched = cs.radius(t, r0)
    assert batched.shape == (r0.size, t.size) and r0.size * t.size > 4 * 8192
    for row, start in zip(batched, r0, strict=True):
        np.testing.assert_array_equal(row, cs.radius(t, start))
    np.testing.assert_array_equal(batched[29], np.ones(t.size))                  # on the cycle it stays there


@pytest.mark.parametrize(("length", "expected"), [(1.0, 8.5), (2.4, 41.0), (5.0, 141.0)])
def test_init_T_reaches_target_and_matches_design_figures(length, expected):
    cs = CanonicalSystem(period=1.5)
    phi0, r0 = cs.init_T(length, 0.7, 1.2)
    assert r0 == pytest.approx(expected, rel=0.01)
    phi, r = cs.state(np.array([0.0, length]), phi0, r0)
    assert r[1] == pytest.approx(1.2, abs=1e-9)
    assert np.mod(phi[1] - 0.7 + np.pi, 2 * np.pi) - np.pi == pytest.approx(0.0, abs=1e-12)
    assert 0.0 <= phi0 < 2 * np.pi


def test_init_T_from_inside_the_cycle():
    cs = CanonicalSystem(period=1.0)
    _, r0 = cs.init_T(0.3, 0.0, 0.9)
    assert r0 < 0.9
    assert cs.radius(np.array([0.3]), r0)[0] == pytest.approx(0.9, abs=1e-9)


def test_tempo_scales_time_exactly():
    slow, fast = CanonicalSystem(period=1.0, tempo=0.5), CanonicalSystem(period=1.0)
    t = np.linspace(0.0, 4.0, 401)
    np.testing.assert_allclose(slow.radius(2 * t, 5.0), fast.radius(t, 5.0), atol=1e-12)
    np.testing.assert_allclose(slow.phase(2 * t, 0.3), fast.phase(t, 0.3), atol=1e-12)


def test_time_between_inverts_radius():
    cs = CanonicalSystem(period=1.0)
    duration = cs.time_between(20.0, 1.5)
    assert cs.radius(np.array([duration]), 20.0)[0] == pytest.approx(1.5, abs=1e-9)


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"period": 0.0}, "period"), ({"period": -1.0}, "period"), ({"period": np.nan}, "period"),
    ({"period": 1.0, "eta": 0.0}, "eta"), ({"period": 1.0, "tempo": -2.0}, "tempo"),
])
def test_bad_constants(kwargs, match):
    with pytest.raises(ValueError, match=match):
        CanonicalSystem(**kwargs)


def test_bad_states():
    cs = CanonicalSystem(period=1.0)
    with pytest.raises(ValueError, match="r0"):
        cs.radius(np.linspace(0, 1, 5), 0.0)
    with pytest.raises(ValueError, match="r0"):
        cs.radius(np.linspace(0, 1, 5), np.nan)
    with pytest.raises(ValueError, match="r_end"):
        cs.init_T(1.0, 0.0, 1.0)
    with pytest.raises(ValueError, match="transient_length"):
        cs.init_T(1.0, 0.0, 0.5)                  # cannot spend 1 s inside the cycle below r = 0.5
    with pytest.raises(ValueError, match="transient_length"):
        cs.init_T(-1.0, 0.0, 1.2)
