"""Shared test setup: headless rendering and one torch thread (set before anything imports them), the benchmarks' helper
modules on the path, a small
fitted DMP for the input-checking suites (a test module may define its own ``demo`` or ``dmp``), and the session
search shared between the tests that search the same recording."""

import os
import sys
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


@pytest.fixture
def shared_session_search(monkeypatch):
    """The library's session search as :func:`_shared_find_sessions` for one test: the CLI's ``fit --demo`` and
    ``fit_sessions`` / ``fit_pose_sessions`` / ``fit_joint`` reuse a search that an earlier test using this fixture
    ran on bit-identical samples (two pose CSVs with the same position columns, say). Everything after the search
    runs as always."""
    from rdmp_gym.agents import fit_sessions as command

    from rdmp_gym.recordings import session_fit

    for module in (session_fit, command):
        monkeypatch.setattr(module, "find_sessions", _shared_find_sessions)
