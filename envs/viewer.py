"""``render_mode="human"``: MuJoCo's interactive viewer (``mujoco.viewer.launch_passive``), where there is
a display; a clear error where there is none (use ``render_mode="rgb_array"`` and a video instead)."""

from __future__ import annotations

import os
import sys
from typing import Any

__all__ = ["HumanViewer", "display_problem"]

_OFFSCREEN_BACKENDS = ("egl", "osmesa")


def display_problem() -> str | None:
    """Why MuJoCo's viewer cannot open here, or None if it can (a display, and a windowing OpenGL backend)."""
    backend = os.environ.get("MUJOCO_GL", "").lower()
    if backend in _OFFSCREEN_BACKENDS:
        return f"MUJOCO_GL={backend} selects offscreen rendering, which has no windows"
    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        return "there is no display (DISPLAY and WAYLAND_DISPLAY are unset)"
    return None


class HumanViewer:
    """A passive MuJoCo viewer window on a scene, opened on the first :meth:`sync`.

    Raises ``ValueError`` at construction when no window can be opened (see :func:`display_problem`).
    """

    def __init__(self, scene: Any) -> None:
        problem = display_problem()
        if problem is not None:
            raise ValueError(f"render_mode: 'human' opens MuJoCo's viewer, but {problem}; use "
                             "render_mode='rgb_array' (or 'depth_array') and a video (RecordEpisodeVideo) instead")
        self.scene = scene
        self._handle: Any = None

    def sync(self) -> None:
        """Show the scene's current state (opens the window the first time)."""
        if self._handle is None:
            import mujoco.viewer

            self._handle = mujoco.viewer.launch_passive(self.scene.model, self.scene.data)
        self._handle.sync()

    def close(self) -> None:
        """Close the window (safe to call twice)."""
        if self._handle is not None:
            self._handle.close()
            self._handle = None
