"""Shared test setup: headless rendering and one torch thread (set before anything imports them), and a small
fitted DMP for the input-checking suites (a test module may define its own ``demo`` or ``dmp``)."""

import os

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_NUM_THREADS", "1")

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
