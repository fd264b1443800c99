"""Property-based fuzzing of the public API (issue 11): every call gives a clear error or a finite result.

"Clear error" means a ``ValueError``/``TypeError`` raised by rdmp-gym's own code (the innermost frame
of the traceback lies in ``rdmp_gym/``, ``envs/`` or ``agents/``), not one that numpy, scipy or mujoco
raised on the way; "finite" means no NaN or inf anywhere in the result. Few examples per property,
derandomized (the same examples on every run) and without deadlines, to keep CI time modest;
``RDMP_FUZZ_EXAMPLES=500`` runs a deeper, randomized search.
"""

import copy
import json
import os
import traceback
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rdmp_gym import PeriodicDMP, RhythmicDMP, load_dmp
from rdmp_gym.dmp.serialization import dmp_from_dict, dmp_to_dict
from rdmp_gym.signals.demonstrations import Demonstration

ROOT = Path(__file__).resolve().parent.parent
OWN_CODE = tuple(str(ROOT / folder) + os.sep for folder in ("rdmp_gym", "envs", "agents"))
EXAMPLES = int(os.environ.get("RDMP_FUZZ_EXAMPLES", "12"))      # e.g. 500 for a deeper, randomized search
FUZZ = settings(max_examples=EXAMPLES, deadline=None, derandomize="RDMP_FUZZ_EXAMPLES" not in os.environ, database=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])

special = st.sampled_from([float("nan"), float("inf"), -float("inf"), 0.0, -1.0, 1e-300, 1e12])
numbers = st.one_of(st.floats(-100.0, 100.0), special, st.integers(-5, 50))
junk = st.one_of(st.none(), st.booleans(), st.text(max_size=3), st.lists(st.floats(-2.0, 2.0), max_size=3),
                 st.dictionaries(st.text(max_size=2), st.integers(), max_size=1))
anything = st.one_of(numbers, junk)


def _finite(value) -> bool:
    """Whether every number inside ``value`` (arrays, tuples, lists, dicts, DMPs) is finite."""
    if isinstance(value, RhythmicDMP):
        return _finite(value.get_params())
    if isinstance(value, np.ndarray):
        return value.dtype.kind not in "fc" or bool(np.all(np.isfinite(value)))
    if isinstance(value, (float, np.floating)):
        return bool(np.isfinite(value))
    if isinstance(value, (list, tuple)):
        return all(_finite(item) for item in value)
    if isinstance(value, dict):
        return all(_finite(item) for item in value.values())
    return True


def clear_or_finite(call):
    """Run ``call``: return its finite result, or None after a ValueError/TypeError raised by our own code."""
    try:
        result = call()
    except (ValueError, TypeError) as error:
        frame = traceback.extract_tb(error.__traceback__)[-1]
        assert frame.filename.startswith(OWN_CODE), \
            f"raw {type(error).__name__} from {frame.filename}:{frame.lineno}: {error}"
        assert str(error), "an error without a message"
        return None
    assert _finite(result), f"non-finite result {result!r}"
    return result


# ---------------------------------------------------------------------------------------- demonstrations
@FUZZ
@given(n=st.integers(0, 600), dt=st.one_of(st.floats(-0.01, 0.02), special), d=st.integers(0, 3),
       period=st.floats(0.05, 5.0), transient=st.floats(0.0, 3.0), noise=st.floats(0.0, 0.2),
       flaw=st.sampled_from(["none", "nan", "inf", "repeat_t", "short_y", "flat"]))
def test_fuzz_demonstrations_and_their_fit(n, dt, d, period, transient, noise, flaw):
    rng = np.random.default_rng(n)
    with np.errstate(all="ignore"):           # non-finite time stamps make non-finite samples: that is the test
        t = np.arange(n) * dt
        Y = np.sin(2 * np.pi * t / period)[:, None] * np.arange(1, d + 1) + np.exp(-t / max(transient, 1e-3))[:, None]
        Y = Y + noise * rng.standard_normal(Y.shape)
    if flaw == "nan" and Y.size:
        Y[n // 2, 0] = np.nan
    elif flaw == "inf" and t.size:
        t[-1] = np.inf
    elif flaw == "repeat_t" and t.size > 2:
        t[2] = t[1]
    elif flaw == "short_y":
        Y = Y[:-1]
    elif flaw == "flat":
        Y = np.zeros_like(Y)
    made = clear_or_finite(lambda: Demonstration(t, Y))
    if made is not None:
        fitted = clear_or_finite(lambda: RhythmicDMP.fit(made, n_periodic=8, n_transient=6))
        if fitted is not None:
            clear_or_finite(lambda: fitted.rollout(made.t))


# ---------------------------------------------------------------------------------------- fit keywords
FIT_KEYWORDS = {"n_periodic": st.one_of(st.integers(-2, 60), anything), "n_transient": st.one_of(st.integers(-2, 40),
                anything), "method": st.one_of(st.sampled_from(["ridge", "lwr"]), junk),
                "alpha_z": numbers, "mu": numbers, "eta": numbers, "period": st.one_of(st.floats(0.5, 2.0), numbers),
                "fading_time": st.one_of(st.floats(0.05, 0.5), numbers), "delta": numbers,
                "periodic_overlap": numbers, "transient_overlap": numbers, "smoothing": numbers,
                "regularization": numbers, "mu1_factor": numbers}


@FUZZ
@given(keywords=st.dictionaries(st.sampled_from(sorted(FIT_KEYWORDS)), st.none(), min_size=1, max_size=3).flatmap(
    lambda chosen: st.fixed_dictionaries({key: FIT_KEYWORDS[key] for key in chosen})))
def test_fuzz_fit_keywords(demo, keywords):
    fitted = clear_or_finite(lambda: RhythmicDMP.fit(demo, **keywords))
    if fitted is not None:
        clear_or_finite(lambda: fitted.rollout(np.linspace(0.0, 4.0, 401)))


@FUZZ
@given(keywords=st.fixed_dictionaries({}, optional={"n_periodic": st.one_of(st.integers(-2, 60), anything),
                                                    "smoothing": numbers, "regularization": numbers,
                                                    "alpha_z": numbers, "method": junk}))
def test_fuzz_periodic_dmp_fit_keywords(demo, keywords):
    fitted = clear_or_finite(lambda: PeriodicDMP.fit(demo, **keywords))
    if fitted is not None:
        clear_or_finite(lambda: fitted.rollout(np.linspace(0.0, 4.0, 401)))


# ---------------------------------------------------------------------------------------- rollouts
vectors = st.one_of(st.none(), st.lists(st.floats(-1.0, 1.0), min_size=1, max_size=4).map(np.array),
                    st.lists(numbers, min_size=3, max_size=3), junk)


@FUZZ
@given(duration=st.one_of(st.floats(0.0, 6.0), special), n=st.integers(0, 800), transient=anything,
       y0=vectors, yd0=vectors, anchor=vectors, scale=st.one_of(st.floats(-3.0, 3.0), vectors),
       rotation=st.one_of(st.none(), st.floats(-7.0, 7.0), special, junk), tempo=st.one_of(st.none(), numbers),
       start_blend=st.booleans(), uneven=st.booleans())
def test_fuzz_rollout_arguments(dmp, duration, n, transient, y0, yd0, anchor, scale, rotation, tempo, start_blend,
                                uneven):
    t = np.linspace(0.0, duration, n) if np.isfinite(duration) else np.full(n, duration)
    if uneven and n > 3:
        t[1] = t[2]
    clear_or_finite(lambda: dmp.rollout(t, transient, y0, yd0, anchor, scale=scale, rotation=rotation,
                                        tempo=tempo, start_blend=start_blend))


@FUZZ
@given(batch=st.integers(0, 4), extra=st.integers(-1, 1), spread=st.one_of(st.floats(0.0, 3.0), special),
       groups=st.one_of(st.none(), st.sampled_from(["periodic", "transient", "initial", "anchor", "amplitude",
                                                    "bogus"]), junk), tempo=st.one_of(st.none(), numbers))
def test_fuzz_rollout_batch(dmp, batch, extra, spread, groups, tempo):
    try:
        thetas = dmp.get_params(groups)
    except (ValueError, TypeError):
        thetas = np.zeros(5)
    thetas = thetas[: thetas.size + extra] if extra <= 0 else np.append(thetas, 0.0)
    rng = np.random.default_rng(batch)
    values = thetas + (spread if np.isfinite(spread) else 1.0) * rng.standard_normal((batch, thetas.size))
    if not np.isfinite(spread) and values.size:
        values[0, 0] = spread
    clear_or_finite(lambda: dmp.rollout_batch(values, np.linspace(0.0, 3.0, 301), groups, tempo=tempo))


# ---------------------------------------------------------------------------------------- DMP files
def _leaves(tree, path=()):
    if isinstance(tree, dict):
        for key, value in tree.items():
            yield from _leaves(value, (*path, key))
    elif isinstance(tree, list) and tree:
        for index, value in enumerate(tree):
            yield from _leaves(value, (*path, index))
    yield path


@FUZZ
@given(data=st.data())
def test_fuzz_dmp_files(dmp, data):
    document = dmp_to_dict(dmp)
    leaves = sorted(_leaves(document), key=str)
    mutated = copy.deepcopy(document)
    for _ in range(data.draw(st.integers(1, 3))):
        path = data.draw(st.sampled_from(leaves))
        value = data.draw(st.one_of(anything, st.just("__delete__")))
        target = mutated
        try:
            for key in path[:-1]:
                target = target[key]
            if not path:
                mutated = value
            elif value == "__delete__" and isinstance(target, dict):
                del target[path[-1]]
            else:
                target[path[-1]] = value
        except (KeyError, IndexError, TypeError):
            continue
    text = json.dumps(mutated)                              # what a file holds (NaN as the JSON extension)
    loaded = clear_or_finite(lambda: dmp_from_dict(json.loads(text)))
    if loaded is not None:
        clear_or_finite(lambda: loaded.rollout(np.linspace(0.0, 3.0, 301)))


# ---------------------------------------------------------------------------------------- env
@pytest.fixture(scope="module")
def env():
    gym = pytest.importorskip("gymnasium")
    import rdmp_gym.envs  # noqa: F401

    environment = gym.make("rdmp_gym/ArmarWipe-v1", disable_env_checker=True, n_periodic=10, n_transient=10,
                           n_periods=1, control_rate=50)
    yield environment
    environment.close()


@FUZZ
@given(options=st.one_of(st.none(), junk, st.dictionaries(
    st.one_of(st.sampled_from(["context", "patch_centre", "patch_size", "table_height", "table_tilt", "obstacle",
                               "dirt", "seed"]), st.text(max_size=4)),
    st.one_of(anything, st.lists(numbers, min_size=1, max_size=12)), max_size=2)),
    action=st.one_of(st.floats(-1.5, 1.5), special, st.just("shape"), junk), seed=st.integers(0, 2**31 - 1))
def test_fuzz_env_reset_options_and_actions(env, options, action, seed):
    reset = clear_or_finite(lambda: env.reset(seed=seed, options=options))
    if reset is None:
        env.reset(seed=seed)
    n = env.action_space.shape[0]
    if action == "shape":
        value = np.zeros(n + 1, dtype=np.float32)
    elif isinstance(action, float):
        value = np.full(n, action, dtype=np.float32) * np.random.default_rng(seed).uniform(0.0, 1.0, n)
    else:
        value = action
    stepped = clear_or_finite(lambda: env.step(value)[:4])
    if stepped is not None:
        assert np.all(np.isfinite(stepped[0])) and np.isfinite(stepped[1])


# ---------------------------------------------------------------------------------------- CLI
def _cli(argv):
    from rdmp_gym.agents.cli import main

    try:
        return main(argv)
    except SystemExit as stop:       # argparse's own usage errors
        return stop.code


@settings(FUZZ, max_examples=max(EXAMPLES * 2 // 3, 1))
@given(flags=st.lists(st.tuples(st.sampled_from(["--n-periodic", "--n-transient", "--method", "--style", "--demo"]),
                                st.one_of(st.integers(-3, 30).map(str), st.sampled_from(["nan", "1e9", "", "x", "lwr",
                                                                                         "2.5", "/nonexistent.csv"]))),
                      max_size=3))
def test_fuzz_cli_fit(tmp_path_factory, flags, capsys):
    out = tmp_path_factory.mktemp("fit")
    argv = ["fit", "--out", str(out), *[part for flag in flags for part in flag]]
    code = _cli(argv)
    assert code in (0, 2), f"{argv} exited with {code}"
    if code == 0:
        dmp = load_dmp(out / "dmp.json")
        assert np.all(np.isfinite(dmp.get_params()))
    else:
        assert capsys.readouterr().err.strip()


@settings(FUZZ, max_examples=max(EXAMPLES // 2, 1))
@given(flags=st.lists(st.tuples(
    st.sampled_from(["--updates", "--rollouts", "--seed", "--perturbation", "--eval-episodes", "--start",
                     "--option", "--env-option", "--reset-option", "--workers", "--agent"]),
    st.sampled_from(["0", "1", "2", "-1", "nan", "1e99", "x", "sigma=0.1", "sigma=-1", "decay=nan", "duration=2.5",
                     "n_periodic=2.5", "bogus=1", "perturbed", "shrunk", "pi2", "cmaes"])), max_size=3))
def test_fuzz_cli_train(tmp_path_factory, flags, capsys):
    from rdmp_gym.envs.registration import TRACKING_ID

    out = tmp_path_factory.mktemp("train") / "run"
    argv = ["train", "--out", str(out), "--env", TRACKING_ID, "--updates", "1", "--rollouts", "2", "--workers", "1",
            "--env-option", "n_periodic", "6", "n_transient", "6", "duration", "2",
            *[part for flag in flags for part in flag]]
    code = _cli(argv)
    assert code in (0, 2), f"{argv} exited with {code}"
    if code == 0:
        records = [json.loads(line) for line in (out / "log.jsonl").read_text().splitlines()]
        assert all(record["eval_return_mean"] is not None for record in records)
    else:
        assert capsys.readouterr().err.strip()
