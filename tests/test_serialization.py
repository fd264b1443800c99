"""The DMP file loader validates every field (issue 11, item 9): NaN, wrong shapes, inconsistent sizes, types."""

import copy
import json

import numpy as np
import pytest

from rdmp_gym import RhythmicDMP, wiping_demonstration
from rdmp_gym.dmp.serialization import dmp_from_dict, dmp_to_dict, load_dmp


@pytest.fixture(scope="module")
def document():
    demo = wiping_demonstration(1, rng=0)
    return dmp_to_dict(RhythmicDMP.fit(demo, n_periodic=8, n_transient=6))


def _changed(document, path, value):
    changed = copy.deepcopy(document)
    target = changed
    for key in path[:-1]:
        target = target[key]
    if value is KeyError:
        del target[path[-1]]
    else:
        target[path[-1]] = value
    return changed


def test_a_saved_dmp_loads_back_exactly(document, tmp_path):
    path = tmp_path / "dmp.json"
    path.write_text(json.dumps(document))
    assert dmp_to_dict(load_dmp(path)) == document


@pytest.mark.parametrize(("path", "value", "field"), [
    (("transients", 0, "start"), [float("nan")] * 3, r"dmp\.transients\[0\]\.start: contains NaN"),
    (("transients", 0, "start_velocity"), [0.0, float("inf"), 0.0], r"transients\[0\]\.start_velocity"),
    (("transients", 0, "length"), float("nan"), r"transients\[0\]\.length: expected a finite positive"),
    (("transients", 0, "start"), [0.1], r"transients\[0\]\.start: expected shape \[3\], got \[1\]"),
    (("basis", "periodic_widths", 2), float("nan"), r"dmp\.basis\.periodic_widths: contains NaN"),
    (("basis", "transient_centres", 1), [float("nan"), 0.0], r"dmp\.basis\.transient_centres: contains NaN"),
    (("basis", "transient_sizes"), [5], r"transient_sizes: they add up to 5, but there are 6"),
    (("basis", "transient_sizes"), [3.5], r"transient_sizes: expected a list of integers"),
    (("basis", "periodic_widths"), [1.0] * 7, r"periodic_widths: expected shape \[8\], got \[7\]"),
    (("canonical", "period"), KeyError, r"dmp\.canonical\.period: missing"),
    (("canonical", "period"), "1.2", r"dmp\.canonical\.period: expected a number, got str"),
    (("canonical",), None, r"dmp\.canonical: expected a JSON object, got NoneType"),
    (("transformation",), None, r"dmp\.transformation: expected a JSON object"),
    (("transformation", "alpha_z"), -1.0, r"alpha_z: expected a finite positive"),
    (("weights", 0, 3), float("nan"), r"dmp\.weights: contains NaN"),
    (("weights",), [[0.0] * 14] * 2, r"dmp\.weights: expected shape \[3, 14\], got \[2, 14\]"),
    (("anchor",), [0.0, True, 0.0], r"dmp\.anchor: expected 1-level nested lists of numbers"),
    (("transients",), [], r"dmp\.transients: expected a list of 1"),
    (("basis", "fading", "mu2"), 0.5, r"fading\.mu2: must exceed mu1"),
    (("extra",), 1, r"dmp: unknown field\(s\) \['extra'\]"),
])
def test_every_broken_field_is_a_value_error_naming_it(document, path, value, field):
    with pytest.raises(ValueError, match=field):
        dmp_from_dict(_changed(document, path, value))


@pytest.mark.parametrize("text", ["[1, 2, 3]", "null", '"dmp"', "{", "\xff\xfe"])
def test_a_file_that_is_not_a_dmp_object_names_the_file(tmp_path, text):
    path = tmp_path / "dmp.json"
    path.write_bytes(text.encode("latin-1"))
    with pytest.raises(ValueError, match=r"dmp\.json: "):
        load_dmp(path)


def test_a_loaded_dmp_rolls_out_finite(document):
    dmp = dmp_from_dict(document)
    assert np.all(np.isfinite(dmp.rollout(np.linspace(0.0, 3.0, 301))))
