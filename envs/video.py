"""Videos of one-step episodes: a wrapper that records what happens *inside* each ``step``.

Gymnasium's ``RecordVideo`` calls ``render()`` after ``reset`` and after each ``step``; an episodic env
(one step = one whole DMP rollout) gives it two frames per episode. :class:`RecordEpisodeVideo` asks the
env for the frames it captures during the rollout (``record_frames``, every ``frame_stride`` control
steps) and writes one video per recorded episode::

    env = RecordEpisodeVideo(gym.make("rdmp_gym/ArmarWipe-v3"), "runs/videos", episode_trigger=lambda i: i % 10 == 0)
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from .recording import write_video

__all__ = ["RecordEpisodeVideo"]


class RecordEpisodeVideo(gym.Wrapper):
    """Writes ``<video_folder>/<name_prefix>-episode-<i>.<format>`` for every episode ``i`` (counted from 0)
    that ``episode_trigger(i)`` selects (default: every episode).

    The wrapped env must expose ``record_frames`` and ``frames`` (``rdmp_gym/ArmarWipe-v*``); ``fps`` defaults
    to its ``metadata["render_fps"]``. ``videos`` lists the files written.
    """

    def __init__(self, env: gym.Env, video_folder: str | Path, episode_trigger: Callable[[int], bool] | None = None,
                 name_prefix: str = "rl-video", video_format: str = "mp4", fps: float | None = None) -> None:
        super().__init__(env)
        base = env.unwrapped
        if not (hasattr(base, "record_frames") and hasattr(base, "frames")):
            raise ValueError(f"env: {base.__class__.__name__} does not capture frames inside a step "
                             "(needs record_frames and frames); use gymnasium's RecordVideo")
        if video_format not in ("mp4", "gif"):
            raise ValueError(f"video_format: expected 'mp4' or 'gif', got {video_format!r}")
        self.video_folder = Path(video_folder)
        self.episode_trigger = episode_trigger or (lambda _: True)
        self.name_prefix, self.video_format = name_prefix, video_format
        self.fps = fps
        self.episode = -1
        self.videos: list[Path] = []

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[Any, dict]:
        self.episode += 1
        return self.env.reset(seed=seed, options=options)

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict]:
        base = self.env.unwrapped
        if not self.episode_trigger(self.episode):
            return self.env.step(action)
        previous = base.record_frames
        base.record_frames = True
        try:
            result = self.env.step(action)
        finally:
            base.record_frames = previous
        frames: list[np.ndarray] = list(base.frames)
        if frames:
            path = self.video_folder / f"{self.name_prefix}-episode-{self.episode}.{self.video_format}"
            fps = self.fps if self.fps is not None else self.env.metadata.get("render_fps", 25)
            self.videos.append(write_video(frames, path, fps=fps))
        return result
