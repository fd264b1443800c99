"""The fit's settings are defined once (:mod:`rdmp_gym.dmp.settings`): the presets, the keyword form and the typed form
give the same DMP, and every default fit reads :data:`DEFAULT_FIT`."""

import dataclasses
import inspect

import numpy as np
import pytest

from rdmp_gym import RhythmicDMP, wiping_demonstration
from rdmp_gym.dmp.fitting import FADE_BEFORE_T, PAPER_SETTINGS, fit_rhythmic
from rdmp_gym.dmp.settings import DEFAULT_FIT, PAPER_FIT, PUBLISHED_ENV_FIT, FitSettings
from rdmp_gym.dmp.stopping import fit_ending
from rdmp_gym.synthetic.demonstrations import ending_demonstration


@pytest.fixture(scope="module")
def demo():
    return wiping_demonstration(1, rng=0)


def test_the_presets_are_frozen_settings_and_the_keyword_dicts_derive_from_them():
    assert DEFAULT_FIT == FitSettings()
    with pytest.raises(dataclasses.FrozenInstanceError):
        DEFAULT_FIT.alpha_z = 25.0
    assert FitSettings(**PAPER_SETTINGS) == PAPER_FIT
    assert DEFAULT_FIT.replace(n_periodic=40, n_transient=40, method="trajectory", **FADE_BEFORE_T) == PUBLISHED_ENV_FIT
    assert PUBLISHED_ENV_FIT.n_periodic == PUBLISHED_ENV_FIT.n_transient == 40
    assert PUBLISHED_ENV_FIT.method == "trajectory"


def test_unknown_settings_are_refused_by_name(demo):
    with pytest.raises(TypeError, match="alpha_y"):
        DEFAULT_FIT.replace(alpha_y=3.0)
    with pytest.raises(TypeError, match="alpha_y"):
        RhythmicDMP.fit(demo, alpha_y=3.0)
    with pytest.raises(TypeError, match="settings"):
        RhythmicDMP.fit(demo, settings={"alpha_z": 5.0})


def test_the_typed_and_the_keyword_forms_give_the_same_dmp(demo):
    keywords = RhythmicDMP.fit(demo, 40, 40, "trajectory", **FADE_BEFORE_T)
    typed = RhythmicDMP.fit(demo, settings=PUBLISHED_ENV_FIT)
    assert np.array_equal(keywords.weights, typed.weights)
    overridden = RhythmicDMP.fit(demo, 20, settings=PUBLISHED_ENV_FIT)
    assert overridden.basis.n_periodic == 20 and overridden.basis.transient_sizes == (40,)


def test_every_default_reads_the_one_source(demo):
    for function in (RhythmicDMP.fit, fit_rhythmic):
        parameters = inspect.signature(function).parameters
        assert all(parameters[name].default is None for name in ("n_periodic", "n_transient", "method"))
    dmp = RhythmicDMP.fit(demo)
    assert dmp.basis.n_periodic == DEFAULT_FIT.n_periodic
    assert dmp.basis.transient_sizes == (DEFAULT_FIT.n_transient,)
    assert dmp.alpha_z == DEFAULT_FIT.alpha_z
    assert inspect.signature(RhythmicDMP).parameters["alpha_z"].default == DEFAULT_FIT.alpha_z


def test_the_stop_fit_takes_the_settings_object_too():
    demo = ending_demonstration(1, rng=0)
    keywords = fit_ending(demo, n_periodic=20, n_transient=20, smoothness=0.3)
    typed = fit_ending(demo, settings=DEFAULT_FIT.replace(n_periodic=20, n_transient=20, smoothness=0.3))
    assert np.array_equal(keywords.ending.weights, typed.ending.weights)
