"""Offscreen rendering of a scene (with dirt cells where a task has them) and video writing.

Rendering uses ``mujoco.Renderer``. Headless machines need an OpenGL backend chosen *before*
``mujoco`` is imported: ``MUJOCO_GL=egl`` (GPU or Mesa llvmpipe, no extra packages) or
``MUJOCO_GL=osmesa`` (software, needs libosmesa). The dirt cells are not bodies of the model; they
are drawn as flat visual-only boxes added to the render scene, brown with an opacity equal to the dirt
left on the cell, and hidden once (almost) clean.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

__all__ = ["SceneRenderer", "write_video"]

logger = logging.getLogger(__name__)

_DIRT_RGBA = np.array([0.45, 0.28, 0.12, 1.0], dtype=np.float32)


class SceneRenderer:
    """Renders RGB frames ``[H, W, 3]`` uint8 of the scene from a named camera.

    Args:
        scene: the scene to draw (anything with a MuJoCo ``model`` and ``data``).
        width, height: frame size in pixels (at most the model's offscreen buffer, 1280 x 960).
        camera: camera name in the model (``front``, ``side``, ``top``) or ``None`` for the free camera.
    """

    def __init__(self, scene: Any, width: int = 480, height: int = 480, camera: str | None = "front"):
        if int(width) < 1 or int(height) < 1:
            raise ValueError(f"width, height: expected positive sizes, got {width}x{height}")
        model = scene.model
        if width > model.vis.global_.offwidth or height > model.vis.global_.offheight:
            raise ValueError(f"width, height: {width}x{height} exceeds the offscreen buffer "
                             f"{model.vis.global_.offwidth}x{model.vis.global_.offheight}")
        if camera is not None and mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, camera) < 0:
            raise ValueError(f"camera: no camera named {camera!r} in the model")
        self.scene = scene
        self.camera = camera if camera is not None else -1
        self.width, self.height = int(width), int(height)
        self._renderer: mujoco.Renderer | None = None

    def _get(self) -> mujoco.Renderer:
        if self._renderer is None:
            self._renderer = mujoco.Renderer(self.scene.model, height=self.height, width=self.width)
        return self._renderer

    def render(self, cells_world: np.ndarray | None = None, dirt: np.ndarray | None = None,
               cell_half: float = 0.005, table_rot: np.ndarray | None = None) -> np.ndarray:
        """Frame of the current state; dirt cells (``cells_world`` [N, 3] with ``dirt`` [N] in [0, 1] left,
        default all dirty) drawn on top."""
        renderer = self._get()
        renderer.update_scene(self.scene.data, camera=self.camera)
        if cells_world is not None and len(cells_world):
            self._add_dirt(renderer.scene, cells_world, dirt, cell_half, table_rot)
        return renderer.render().copy()

    def render_depth(self) -> np.ndarray:
        """Depth frame ``[H, W]`` float32: distance (m) from the camera plane to the nearest surface."""
        renderer = self._get()
        renderer.update_scene(self.scene.data, camera=self.camera)
        renderer.enable_depth_rendering()
        try:
            return renderer.render().astype(np.float32)
        finally:
            renderer.disable_depth_rendering()

    @staticmethod
    def _add_dirt(scn: mujoco.MjvScene, cells: np.ndarray, dirt: np.ndarray | None, half: float,
                  rot: np.ndarray | None) -> None:
        mat = (np.eye(3) if rot is None else rot).ravel()
        size = np.array([half * 0.92, half * 0.92, 0.0008])
        for index, centre in enumerate(cells):
            level = 1.0 if dirt is None else float(dirt[index])
            if level < 0.02:
                continue
            if scn.ngeom >= scn.maxgeom:
                logger.warning("render scene full: %d dirt cells not drawn", len(cells) - index)
                break
            pos = centre + mat.reshape(3, 3)[:, 2] * 0.0009
            rgba = _DIRT_RGBA.copy()
            rgba[3] = min(1.0, level)
            mujoco.mjv_initGeom(scn.geoms[scn.ngeom], mujoco.mjtGeom.mjGEOM_BOX, size, pos, mat, rgba)
            scn.ngeom += 1

    def close(self) -> None:
        """Free the OpenGL context (safe to call twice)."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None


def write_video(frames: Sequence[np.ndarray], path: str | Path, fps: float = 30.0) -> Path:
    """Write RGB frames ``[H, W, 3]`` uint8 to ``path`` (``.mp4`` via ffmpeg, or ``.gif``) with imageio."""
    import imageio.v2 as imageio

    path = Path(path)
    if not frames:
        raise ValueError("frames: nothing to write")
    if fps <= 0:
        raise ValueError(f"fps: expected a positive number, got {fps!r}")
    path.parent.mkdir(parents=True, exist_ok=True)
    if path.suffix.lower() == ".gif":
        imageio.mimsave(path, list(frames), duration=1.0 / fps, loop=0)
    else:
        with imageio.get_writer(path, fps=fps, codec="libx264", quality=7, macro_block_size=8) as writer:
            for frame in frames:
                writer.append_data(frame)
    logger.info("wrote %d frames to %s", len(frames), path)
    return path
