"""Basis functions and fading (paper eqs. (7)-(9))."""

import numpy as np
import pytest

from rdmp_gym import CanonicalSystem, Fading, RhythmicDMP, wiping_demonstration
from rdmp_gym.dmp.basis import periodic_width, transient_basis_along_path, transient_times
from rdmp_gym.dmp.fitting import FADE_BEFORE_T


@pytest.fixture(scope="module")
def dmp():
    demo = wiping_demonstration(1, rng=0)
    return RhythmicDMP.fit(demo, n_periodic=20, n_transient=20)


def test_fading_gates():
    fading = Fading(mu1=1.2, mu2=1.8, delta=1e-3)
    r_low = np.linspace(0.05, 1.2, 50)
    np.testing.assert_array_equal(fading.periodic_gate(r_low), 1.0)        # g = 1 below mu1
    assert np.all(fading.transient_gate(r_low) <= 1e-3 + 1e-15)            # a <= delta below mu1
    assert fading.periodic_gate(np.array([1.8]))[0] == pytest.approx(1e-3)
    assert fading.transient_gate(np.array([1.2]))[0] == pytest.approx(1e-3)
    np.testing.assert_array_equal(fading.transient_gate(np.linspace(1.8, 50, 20)), 1.0)
    r = np.linspace(1.2, 1.8, 200)
    assert np.all(np.diff(fading.periodic_gate(r)) <= 0) and np.all(np.diff(fading.transient_gate(r)) >= 0)


def test_fading_rejects_bad_radii():
    with pytest.raises(ValueError, match="mu2"):
        Fading(mu1=1.2, mu2=1.1)
    with pytest.raises(ValueError, match="delta"):
        Fading(mu1=1.2, mu2=1.5, delta=2.0)


def test_periodic_width_gives_requested_overlap():
    v = periodic_width(40, overlap=0.5)
    half_spacing = np.pi / 40
    assert np.exp(v * (np.cos(half_spacing) - 1)) == pytest.approx(0.5)


def test_transient_centres_uniform_in_time_on_the_path():
    cs = CanonicalSystem(period=1.5)
    phi0, r0 = cs.init_T(2.0, 0.0, 1.2)
    centres, widths = transient_basis_along_path(cs, phi0, r0, 1.8, 10)
    phi, r = cs.state(np.linspace(0, 1.8, 10), phi0, r0)
    np.testing.assert_allclose(centres, np.stack([r * np.cos(phi), r * np.sin(phi)], 1), atol=1e-12)
    # the support (level delta) never reaches the next turn of the spiral
    next_turn = r - cs.radius(np.linspace(0, 1.8, 10) + 1.5, r0)
    assert np.all(np.exp(-widths * next_turn**2) <= 1e-3 + 1e-12)


@pytest.mark.parametrize("settings", [{}, FADE_BEFORE_T])
def test_only_periodic_basis_after_the_fade_and_transient_before(settings):
    """The families hand over in the ``t_f`` after T (default) or before it (``FADE_BEFORE_T``); the mixture keeps
    a steady share of the floor on the path (the activations sum to about 2 there)."""
    dmp = RhythmicDMP.fit(wiping_demonstration(1, rng=0), n_periodic=20, n_transient=20, **settings)
    start = dmp.transients[0]
    t = np.arange(0, 8.0, 0.01)
    phi, r = dmp.canonical.state(t, start.phi0, start.r0)
    act = dmp.basis.normalized(phi, r)
    periodic_share = act[:, : dmp.basis.n_periodic].sum(1)
    fading = dmp.basis.fading
    t_f = dmp.canonical.time_between(fading.mu2, fading.mu1)
    fade_end = start.length + (t_f if settings.get("handover", "after") == "after" else 0.0)
    total = act.sum(1)
    lowest = 1.0 / (1.0 + 2.0 * fading.floor)                     # the floor takes at most a third of a sum of 1
    assert np.all(total > lowest) and np.all(total <= 1.0)
    assert np.all(periodic_share[t >= fade_end] > total[t >= fade_end] - 1e-3)
    assert np.all(periodic_share[t < 0.5 * start.length] < 1e-3)
    assert np.any(periodic_share[t < fade_end] < 0.5 * total[t < fade_end])     # the fade is not over sooner


def test_transient_times_lead_the_start():
    times = transient_times(1.8, 10, lead=1.0)
    assert times[-1] == pytest.approx(1.8) and times[1] == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_allclose(np.diff(times), 1.8 / 8)                 # 8 spacings from the start to 1.8 s
    np.testing.assert_allclose(transient_times(1.8, 10), np.linspace(0.0, 1.8, 10))
    assert transient_times(1.8, 2, lead=1.0)[0] == 0.0                 # one centre stays at or after the start
    with pytest.raises(ValueError, match="transient_lead"):
        transient_times(1.8, 10, lead=-1.0)


def test_normalised_mixture_is_finite_far_from_every_support(dmp):
    t = np.arange(0, 5.0, 0.01)
    phi, r = dmp.canonical.state(t, 1.0, 300.0)                # a path no basis function was placed on
    act = dmp.basis.normalized(phi, r)
    assert np.all(np.isfinite(act)) and np.all(act.sum(1) <= 1.0 + 1e-12)
    forcing = act @ dmp.weights.T
    assert np.all(np.isfinite(forcing))
