"""Shared test setup: headless rendering and one torch thread (set before anything imports them)."""

import os

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_NUM_THREADS", "1")
