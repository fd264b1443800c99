"""Shared test setup: headless rendering and one torch thread (set before anything imports them), the benchmarks' helper
modules on the path, and a small
fitted DMP for the input-checking suites (a test module may define its own ``demo`` or ``dmp``)."""

import os
import sys
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_NUM_THREADS", "1")
# the experiment scaffolding the tests check (probes, the obstacle baseline) lives with the benchmarks
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))

import pytest

from rdmp_gym import RhythmicDMP, wiping_demonstration


@pytest.fixture(scope="module")
def demo():
    """Built-in wiping style 1, seed 0."""
    return wiping_demonstration(1, rng=0)


@pytest.fixture(scope="module")
def dmp(demo):
    """A small DMP (N = 10, M = 8) fitted to ``demo``."""
    return RhythmicDMP.fit(demo, n_periodic=10, n_transient=8)
