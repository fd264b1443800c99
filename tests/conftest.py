"""Shared test setup: headless rendering and one torch thread (set before anything imports them), the benchmarks' helper
modules on the path, a small
fitted DMP for the input-checking suites (a test module may define its own ``demo`` or ``dmp``), and the session
search shared between the tests and module fixtures that search the same recording."""

import contextlib
import os
import sys
from collections.abc import Iterator
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_NUM_THREADS", "1")
# the experiment scaffolding the tests check (probes, the obstacle baseline) lives with the benchmarks
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))

import pytest

from rdmp_gym import RhythmicDMP, wiping_demonstration
from rdmp_gym.signals.demonstrations import Demonstration
from rdmp_gym.signals.segmentation import sessions as _sessions_module


@pytest.fixture(scope="module")
def demo():
    """Built-in wiping style 1, seed 0."""
    return wiping_demonstration(1, rng=0)


@pytest.fixture(scope="module")
def dmp(demo):
    """A small DMP (N = 10, M = 8) fitted to ``demo``."""
    return RhythmicDMP.fit(demo, n_periodic=10, n_transient=8)


_SEARCHES: dict[tuple, tuple] = {}
_find_sessions = _sessions_module.find_sessions


def _shared_find_sessions(demo, **kwargs):
    """``find_sessions(demo, **kwargs)``, searched once per test process for the same samples (the most expensive
    step of the suite: a 2-3 session recording costs 3-10 CPU s). The search is a deterministic function of
    ``demo.t``, ``demo.Y`` and the keywords; its :class:`~rdmp_gym.signals.segmentation.sessions.Session` items are
    frozen, so every caller gets a new list of the same items. A search that raises is not stored (it raises again)."""
    if not isinstance(demo, Demonstration):
        return _find_sessions(demo, **kwargs)
    key = (demo.t.shape, demo.t.tobytes(), demo.Y.shape, demo.Y.tobytes(), tuple(sorted(kwargs.items())))
    if key not in _SEARCHES:
        _SEARCHES[key] = tuple(_find_sessions(demo, **kwargs))
    return list(_SEARCHES[key])


def _share_searches(patch: pytest.MonkeyPatch) -> None:
    """Route the session searches of the CLI's ``fit --demo`` and of ``fit_sessions`` / ``fit_pose_sessions`` /
    ``fit_joint`` through :func:`_shared_find_sessions`."""
    from rdmp_gym.agents import fit_sessions as command

    from rdmp_gym.recordings import session_fit

    for module in (session_fit, command):
        patch.setattr(module, "find_sessions", _shared_find_sessions)


@pytest.fixture
def shared_session_search(monkeypatch):
    """The library's session search as :func:`_shared_find_sessions` for one test: the CLI's ``fit --demo`` and
    ``fit_sessions`` / ``fit_pose_sessions`` / ``fit_joint`` reuse a search that an earlier test or module fixture
    using the shared search ran on bit-identical samples (two pose CSVs with the same position columns, a module
    fixture's fit of :func:`fit_command_demonstration`'s samples and the CLI's fit of the same CSV, say). Everything
    after the search runs as always."""
    _share_searches(monkeypatch)


@pytest.fixture(scope="session")
def sharing_session_search():
    """``with sharing_session_search(): ...``: :func:`shared_session_search` for a block of code, e.g. a module
    fixture's fit whose search a later test's CLI fit of the same samples reuses."""

    @contextlib.contextmanager
    def sharing() -> Iterator[None]:
        with pytest.MonkeyPatch.context() as patch:
            _share_searches(patch)
            yield

    return sharing


@pytest.fixture(scope="session")
def fit_command_demonstration():
    """``read(path) -> Demonstration``: the samples that ``rdmp-gym fit --demo PATH`` fits for a CSV of positions
    (read with the command's default time column and rate, then despiked), so that a test's own fit of them shares
    the command's search."""
    from rdmp_gym.agents.imitation import load_demonstration

    from rdmp_gym.signals.filters import despike

    def read(path) -> Demonstration:
        loaded = load_demonstration(str(path), time_column="t", rate=100.0)
        return Demonstration(loaded.t, despike(loaded.Y), name=loaded.name)

    return read


@pytest.fixture
def no_learning_curve_figure(monkeypatch):
    """``train`` without drawing ``learning_curve.png`` (~0.4 CPU s a run, most of a tiny run's time), for tests that
    check a run's numbers, log, checkpoints and locks, never the figure. The figure of runs like theirs is drawn and
    checked by the tests that read it (``test_agents_runs.py``'s run directory, ``test_agents_env.py``'s command
    line) and drawn by every other test that trains."""
    from rdmp_gym.agents import training

    monkeypatch.setattr(training, "plot_learning_curve", lambda records, path, title="", metrics=None: None)
