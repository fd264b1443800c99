"""A run directory: ``config.json``, ``log.jsonl`` (one line per update), checkpoints, best parameters.

Layout::

    config.json        the run's configuration (what ``--resume`` continues)
    log.jsonl          one JSON object per update (update 0 = the start, before any learning)
    checkpoint.pkl     state after the last completed update (written atomically)
    best_params.npy    [n] action of the best policy so far
    best_params.json   that action, its DMP parameters and its evaluation
    dmp.json           the best policy's refined DMP (core format: gym.make(env_id, dmp=...), RhythmicDMP.load)
    learning_curve.png

The log is appended before the checkpoint is replaced; on resume, lines beyond the checkpoint's
update are dropped and redone, so a killed run loses no completed update and logs none twice.
Checkpoints are pickles: load only run directories you trust.
"""

from __future__ import annotations

import json
import logging
import os
import pickle
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["RunDirectory"]

logger = logging.getLogger(__name__)


def _write_atomic(path: Path, data: bytes) -> None:
    temporary = path.with_name(path.name + ".tmp")
    with temporary.open("wb") as handle:
        handle.write(data)
        handle.flush()
        os.fsync(handle.fileno())
    os.replace(temporary, path)


class RunDirectory:
    """Files of one training run.

    Args:
        path: the directory.
    """

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.config_path = self.path / "config.json"
        self.log_path = self.path / "log.jsonl"
        self.checkpoint_path = self.path / "checkpoint.pkl"
        self.best_npy = self.path / "best_params.npy"
        self.best_json = self.path / "best_params.json"
        self.curve_png = self.path / "learning_curve.png"

    def create(self, config: dict[str, Any]) -> None:
        """Start a new run: make the directory and write ``config.json``.

        Raises ``FileExistsError`` if the directory already holds a run (use resume instead).
        """
        if self.config_path.exists():
            raise FileExistsError(f"out: {self.path} already holds a run; pass --resume or choose another --out")
        self.path.mkdir(parents=True, exist_ok=True)
        _write_atomic(self.config_path, (json.dumps(config, indent=2, sort_keys=True) + "\n").encode())

    def read_config(self) -> dict[str, Any]:
        """The run's configuration."""
        if not self.config_path.exists():
            raise FileNotFoundError(f"run: {self.path} has no config.json (not a run directory)")
        return json.loads(self.config_path.read_text())

    def append_log(self, record: dict[str, Any]) -> None:
        """Append one update's record as a JSON line (flushed to disk)."""
        with self.log_path.open("a") as handle:
            handle.write(json.dumps(record, sort_keys=True) + "\n")
            handle.flush()
            os.fsync(handle.fileno())

    def read_log(self) -> list[dict[str, Any]]:
        """All logged records, in order."""
        if not self.log_path.exists():
            return []
        return [json.loads(line) for line in self.log_path.read_text().splitlines() if line.strip()]

    def truncate_log(self, last_update: int) -> None:
        """Keep only the records with ``update <= last_update``."""
        kept = [record for record in self.read_log() if record["update"] <= last_update]
        _write_atomic(self.log_path, "".join(json.dumps(r, sort_keys=True) + "\n" for r in kept).encode())

    def save_checkpoint(self, state: dict[str, Any]) -> None:
        """Replace the checkpoint with ``state`` (atomically)."""
        _write_atomic(self.checkpoint_path, pickle.dumps(state))

    def load_checkpoint(self) -> dict[str, Any] | None:
        """The last checkpoint, or None if the run has none yet."""
        if not self.checkpoint_path.exists():
            return None
        with self.checkpoint_path.open("rb") as handle:
            return pickle.load(handle)

    def save_best(self, action: np.ndarray, params: np.ndarray, summary: dict[str, Any]) -> None:
        """Write the best policy: ``action [n]`` to ``best_params.npy``; action, ``params [P]`` and
        ``summary`` (its evaluation) to ``best_params.json``."""
        np.save(self.best_npy, np.asarray(action, dtype=np.float64))
        document = {**summary, "action": np.asarray(action).tolist(), "params": np.asarray(params).tolist()}
        _write_atomic(self.best_json, (json.dumps(document, indent=2, sort_keys=True) + "\n").encode())

    def load_best(self) -> np.ndarray:
        """``[n]`` the best action saved by the run."""
        if not self.best_npy.exists():
            raise FileNotFoundError(f"run: {self.path} has no best_params.npy yet")
        return np.load(self.best_npy)
