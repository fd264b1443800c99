"""A run directory: configuration, provenance, log, checkpoint and best parameters of one training run.

Layout::

    config.json            the run's configuration (what ``--resume`` continues); ``demo`` is run-relative
    provenance.json        package versions, rdmp-gym version and git commit, the demonstration's source
                           and sha256; one entry per start or resume of the run
    demo.csv | demo.npz    a copy of the demonstration the run imitates (if it was given one)
    log.jsonl              one JSON object per update (update 0 = the start, before any learning)
    checkpoint.json        state after the last completed update: numbers, strings, RNG states, and the
                           sha256 of each file that holds the rest
    checkpoint-<U>.npz     its arrays (read without pickle)
    checkpoint-<U>-*.zip   its SB3 models (PPO), read weights-only
    best_params.npy        [n] action of the best policy so far
    best_params.json       that action, its DMP parameters and its evaluation
    dmp.json               the best policy's refined DMP (core format: gym.make(env_id, dmp=...), rdmp_gym.load_dmp)
    learning_curve.png
    .lock                  held by the process that writes the run

Every file is written atomically (a temporary file, fsync, rename). The log is appended before the
checkpoint is replaced; on resume, lines beyond the checkpoint's update are dropped and redone, so a
killed run loses no completed update and logs none twice. Every file that is read back is validated:
a broken one is a ``ValueError`` that names the file and what to do. Nothing that is read runs code
(no pickle); ``checkpoint.pkl`` of older versions is refused.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import logging
import math
import os
import reprlib
import shutil
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import filelock
import numpy as np

from rdmp_gym.validation import is_number

from .state_files import decode, encode

__all__ = ["CHECKPOINT_FIELDS", "CHECKPOINT_FORMAT", "RunDirectory", "RunLockedError", "sha256_file", "write_atomic"]

logger = logging.getLogger(__name__)

CHECKPOINT_FORMAT = "rdmp-gym/checkpoint"
CHECKPOINT_VERSION = 2
_ZIP_MAGIC = b"PK\x03\x04"


def _is_count(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and value >= 0


#: the checkpoint's top-level fields (what training writes after every update): name -> (check, what it must be)
CHECKPOINT_FIELDS: dict[str, tuple[Callable[[Any], bool], str]] = {
    "update": (_is_count, "a count (an integer >= 0)"),
    "episodes": (_is_count, "a count (an integer >= 0)"),
    "elapsed": (lambda value: is_number(value) and math.isfinite(value) and value >= 0,
                "seconds (a finite number >= 0)"),
    "best": (lambda value: value is None or (isinstance(value, dict) and is_number(value.get("eval_return_mean"))),
             "None or the best policy's summary (a dict with a number 'eval_return_mean')"),
    "agent": (lambda value: isinstance(value, dict), "the agent's state (a dict)"),
}


class RunLockedError(BlockingIOError):
    """Another process is writing the run directory."""


def write_atomic(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file and a rename (no torn file after a crash)."""
    temporary = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        with temporary.open("wb") as handle:
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(temporary, path)
    finally:
        temporary.unlink(missing_ok=True)


def _json_bytes(document: Any) -> bytes:
    return (json.dumps(document, indent=2, sort_keys=True, allow_nan=False) + "\n").encode()


def sha256_file(path: Path) -> str:
    """The SHA-256 of the file at ``path`` (hex), read in blocks of 1 MiB."""
    digest = hashlib.sha256()
    with path.open("rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _strict_float(text: str) -> float:
    raise ValueError(f"non-standard JSON number {text}")


class RunDirectory:
    """Files of one training run.

    Args:
        path: the directory.
    """

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.config_path = self.path / "config.json"
        self.provenance_path = self.path / "provenance.json"
        self.log_path = self.path / "log.jsonl"
        self.checkpoint_path = self.path / "checkpoint.json"
        self.legacy_checkpoint_path = self.path / "checkpoint.pkl"
        self.best_npy = self.path / "best_params.npy"
        self.best_json = self.path / "best_params.json"
        self.curve_png = self.path / "learning_curve.png"
        self.lock_path = self.path / ".lock"

    # ------------------------------------------------------------------ opening
    @contextlib.contextmanager
    def open(self, new: bool) -> Iterator[RunDirectory]:
        """Hold the run's lock while writing it; refuse what cannot be written or would mix two runs.

        ``new``: the directory must not exist or be empty (else ``FileExistsError``); otherwise it must
        hold a run (``config.json``). If the body of a new run fails before ``config.json`` is written,
        what it wrote is removed again (and the directory, if this call created it). Raises
        :class:`RunLockedError` if another process holds the lock and ``PermissionError`` if the
        directory cannot be written.
        """
        created = new and not self.path.exists()
        stray_lock = not self.lock_path.exists()       # remove the lock file again if the run is refused
        if not new and not self.config_path.exists():
            raise FileNotFoundError(f"run: {self.path} has no config.json (not a run directory); "
                                    "start a new run instead of --resume")
        try:
            self.path.mkdir(parents=True, exist_ok=True)
            lock = filelock.FileLock(self.lock_path, timeout=0)
            lock.acquire()
        except filelock.Timeout as error:
            raise RunLockedError(f"out: {self.path} is being written by another process (it holds "
                                 f"{self.lock_path}); wait for it or choose another --out") from error
        except OSError as error:
            raise PermissionError(f"out: cannot write to {self.path} ({error.strerror or error}); "
                                  "choose a writable --out") from error
        try:
            self.check_writable()
            if new:
                self._check_empty()
        except BaseException:
            lock.release()
            if created:
                shutil.rmtree(self.path, ignore_errors=True)
            elif stray_lock:
                self.lock_path.unlink(missing_ok=True)
            raise
        try:
            yield self
        except BaseException:
            if new and not self.config_path.exists():     # nothing of a run was written: leave no trace
                lock.release()
                if created:
                    shutil.rmtree(self.path, ignore_errors=True)
                else:
                    for entry in self.path.iterdir():
                        shutil.rmtree(entry) if entry.is_dir() else entry.unlink(missing_ok=True)
            raise
        finally:
            lock.release()

    def _check_empty(self) -> None:
        if self.config_path.exists():
            raise FileExistsError(f"out: {self.path} already holds a run; pass --resume or choose another --out")
        others = sorted(p.name for p in self.path.iterdir() if p != self.lock_path)
        if others:
            shown = ", ".join(others[:5]) + (", ..." if len(others) > 5 else "")
            raise FileExistsError(f"out: {self.path} holds files ({shown}) but no config.json; a new run "
                                  "needs an empty or new directory")

    def check_writable(self) -> None:
        """Raise ``PermissionError`` naming the directory unless a file can be written into it."""
        probe = self.path / f".write-test.{os.getpid()}"
        try:
            write_atomic(probe, b"")
            probe.unlink()
        except OSError as error:
            raise PermissionError(f"out: cannot write to {self.path} ({error.strerror or error}); "
                                  "choose a writable directory") from error

    # ------------------------------------------------------------------ JSON documents
    def _read_json(self, path: Path, what: str) -> Any:
        if not path.exists():
            raise FileNotFoundError(f"{path}: missing ({what})")
        try:
            return json.loads(path.read_text(encoding="utf-8"), parse_constant=_strict_float)
        except (ValueError, UnicodeDecodeError) as error:
            raise ValueError(f"{path}: broken JSON ({error}); restore the file or start a new run") from error

    def write_config(self, config: dict[str, Any]) -> None:
        """Write ``config.json`` (a new run)."""
        write_atomic(self.config_path, _json_bytes(config))

    def read_config(self) -> dict[str, Any]:
        """The run's configuration (a JSON object)."""
        if not self.config_path.exists():
            raise FileNotFoundError(f"run: {self.path} has no config.json (not a run directory)")
        config = self._read_json(self.config_path, "the run's configuration")
        if not isinstance(config, dict):
            raise ValueError(f"{self.config_path}: expected a JSON object, got {type(config).__name__}; "
                             "restore the file or start a new run")
        return config

    def read_provenance(self) -> dict[str, Any]:
        """``provenance.json`` (an empty record for runs written before it existed)."""
        if not self.provenance_path.exists():
            return {"sessions": []}
        document = self._read_json(self.provenance_path, "the run's provenance")
        if not isinstance(document, dict) or not isinstance(document.get("sessions"), list):
            raise ValueError(f"{self.provenance_path}: expected an object with a 'sessions' list; "
                             "restore the file or delete it")
        return document

    def write_provenance(self, document: dict[str, Any]) -> None:
        """Replace ``provenance.json``."""
        write_atomic(self.provenance_path, _json_bytes(document))

    # ------------------------------------------------------------------ log
    def append_log(self, record: dict[str, Any]) -> None:
        """Append one update's record as a JSON line (flushed to disk)."""
        line = json.dumps(record, sort_keys=True, allow_nan=False) + "\n"
        with self.log_path.open("a", encoding="utf-8") as handle:
            handle.write(line)
            handle.flush()
            os.fsync(handle.fileno())

    def _parse_log(self) -> tuple[list[dict[str, Any]], bool]:
        """The complete records, and whether a torn last line followed them."""
        if not self.log_path.exists():
            return [], False
        text = self.log_path.read_text(encoding="utf-8", errors="replace")
        lines = text.split("\n")
        records, torn = [], False
        for number, line in enumerate(lines, start=1):
            if not line.strip():
                continue
            last = number == len(lines)       # no newline after it: the write was cut off
            try:
                record = json.loads(line, parse_constant=_strict_float)
                if not isinstance(record, dict) or isinstance(record.get("update"), bool) \
                        or not isinstance(record.get("update"), int):
                    raise ValueError("expected an object with an integer 'update'")
            except ValueError as error:
                if last:
                    torn = True
                    break
                raise ValueError(f"{self.log_path}: line {number} is broken ({error}); delete that line and "
                                 "every later one, then --resume redoes those updates") from error
            if last:
                torn = True               # complete JSON but no newline: treat as torn too
                break
            records.append(record)
        return records, torn

    def read_log(self) -> list[dict[str, Any]]:
        """All complete logged records, in order (a torn last line is skipped with a warning)."""
        records, torn = self._parse_log()
        if torn:
            logger.warning("%s: the last line is incomplete (the run was interrupted); it is ignored", self.log_path)
        return records

    def truncate_log(self, last_update: int) -> None:
        """Keep only the records with ``update <= last_update``, which must be ``0, 1, ..., last_update``.

        A torn last line is dropped with a warning. Missing or repeated updates are a ``ValueError``.
        """
        records, torn = self._parse_log()
        if torn:
            logger.warning("%s: dropped an incomplete last line (the run was interrupted)", self.log_path)
        kept = [record for record in records if record["update"] <= last_update]
        updates = [record["update"] for record in kept]
        if updates != list(range(last_update + 1)):
            raise ValueError(f"{self.log_path}: holds updates {updates}, expected 0 to {last_update} "
                             "(the checkpoint's); the log is not this run's or lost lines; start a new run")
        if torn or len(kept) != len(records):
            write_atomic(self.log_path, "".join(json.dumps(r, sort_keys=True) + "\n" for r in kept).encode())

    # ------------------------------------------------------------------ checkpoint
    def save_checkpoint(self, state: dict[str, Any]) -> None:
        """Replace the checkpoint with ``state`` (a state tree, see :mod:`rdmp_gym.agents.state_files`).

        Arrays go to ``checkpoint-<U>.npz``, byte strings (SB3 models) to ``checkpoint-<U>-<key>.zip``,
        the rest to ``checkpoint.json`` with the sha256 of those files; older files are removed after.
        """
        update = int(state["update"])
        arrays: dict[str, np.ndarray] = {}
        blobs: dict[str, bytes] = {}
        tree = encode(state, arrays, blobs)
        files: dict[str, str] = {}
        npz = self.path / f"checkpoint-{update}.npz"
        temporary = self.path / f".checkpoint-{update}.{os.getpid()}.npz"
        try:
            with temporary.open("wb") as handle:
                np.savez(handle, **arrays)
                handle.flush()
                os.fsync(handle.fileno())
            os.replace(temporary, npz)
        finally:
            temporary.unlink(missing_ok=True)
        files["arrays"] = npz.name
        for key, blob in blobs.items():
            suffix = ".zip" if blob.startswith(_ZIP_MAGIC) else ".bin"
            target = self.path / f"checkpoint-{update}-{key}{suffix}"
            write_atomic(target, blob)
            files[key] = target.name
        hashes = {name: sha256_file(self.path / name) for name in files.values()}
        document = {"format": CHECKPOINT_FORMAT, "version": CHECKPOINT_VERSION, "update": update,
                    "files": files, "sha256": hashes, "state": tree}
        write_atomic(self.checkpoint_path, _json_bytes(document))
        for stale in self.path.glob("checkpoint-*"):
            if stale.name not in hashes:
                stale.unlink(missing_ok=True)

    def load_checkpoint(self) -> dict[str, Any] | None:
        """The last checkpoint's state tree, or None if the run has none yet.

        Raises ``ValueError`` naming the file for a pickle checkpoint, a broken or inconsistent one, and naming the
        file and the field for a field of :data:`CHECKPOINT_FIELDS` of the wrong type or range.
        """
        if not self.checkpoint_path.exists():
            if self.legacy_checkpoint_path.exists():
                raise ValueError(f"{self.legacy_checkpoint_path}: a pickle checkpoint of an older rdmp-gym; pickles "
                                 "can run code when loaded and are no longer read; start a new run (its "
                                 "best_params.npy is still usable with `evaluate --policy best`)")
            return None
        document = self._read_json(self.checkpoint_path, "the last checkpoint")
        redo = "delete checkpoint.json and checkpoint-*.* to restart the run, or start a new run"
        if not isinstance(document, dict) or document.get("format") != CHECKPOINT_FORMAT:
            raise ValueError(f"{self.checkpoint_path}: not an rdmp-gym checkpoint; {redo}")
        if document.get("version") != CHECKPOINT_VERSION:
            raise ValueError(f"{self.checkpoint_path}: checkpoint version {document.get('version')!r}, this "
                             f"rdmp-gym reads {CHECKPOINT_VERSION}; {redo}")
        files, hashes = document.get("files"), document.get("sha256")
        if not isinstance(files, dict) or not isinstance(hashes, dict) or "arrays" not in files \
                or any(not isinstance(n, str) or Path(n).name != n for n in files.values()):
            raise ValueError(f"{self.checkpoint_path}: 'files' is missing or broken; {redo}")
        for name in files.values():
            path = self.path / name
            if not path.exists():
                raise ValueError(f"{path}: missing (named by checkpoint.json); {redo}")
            if sha256_file(path) != hashes.get(name):
                raise ValueError(f"{path}: does not match the sha256 in checkpoint.json (changed or torn); {redo}")
        try:
            with np.load(self.path / files["arrays"], allow_pickle=False) as archive:
                arrays = {key: archive[key] for key in archive.files}
        except (OSError, ValueError, EOFError) as error:
            raise ValueError(f"{self.path / files['arrays']}: unreadable ({error}); {redo}") from error
        blobs = {key: (self.path / name).read_bytes() for key, name in files.items() if key != "arrays"}
        try:
            state = decode(document.get("state"), arrays, blobs)
        except ValueError as error:
            raise ValueError(f"{self.checkpoint_path}: {error}; {redo}") from error
        if not isinstance(state, dict) or state.get("update") != document.get("update"):
            raise ValueError(f"{self.checkpoint_path}: the state does not match its update; {redo}")
        for name, (fits, expected) in CHECKPOINT_FIELDS.items():
            if not fits(state.get(name)):
                raise ValueError(f"{self.checkpoint_path}: the field {name!r} is {reprlib.repr(state.get(name))}, "
                                 f"expected {expected}; {redo}")
        return state

    # ------------------------------------------------------------------ best parameters
    def save_best(self, action: np.ndarray, params: np.ndarray, summary: dict[str, Any]) -> None:
        """Write the best policy: ``action [n]`` to ``best_params.npy``; action, ``params [P]`` and
        ``summary`` (its evaluation) to ``best_params.json``."""
        action = np.asarray(action, dtype=np.float64)
        buffer = io.BytesIO()
        np.save(buffer, action)
        write_atomic(self.best_npy, buffer.getvalue())
        document = {**summary, "action": action.tolist(), "params": np.asarray(params).tolist()}
        write_atomic(self.best_json, _json_bytes(document))

    def load_best(self, n_actions: int | None = None) -> np.ndarray:
        """``[n]`` the best action saved by the run, validated (finite, in ``[-1, 1]``, ``n_actions`` long)."""
        if not self.best_npy.exists():
            raise FileNotFoundError(f"run: {self.path} has no best_params.npy yet")
        try:
            action = np.load(self.best_npy, allow_pickle=False)
        except (OSError, ValueError, EOFError) as error:
            raise ValueError(f"{self.best_npy}: unreadable ({error}); copy 'action' from best_params.json "
                             "back into it, or use --policy last") from error
        if action.ndim != 1 or action.dtype.kind != "f" or not np.all(np.isfinite(action)) \
                or np.any(np.abs(action) > 1.0) or (n_actions is not None and action.size != n_actions):
            expected = f"{n_actions} " if n_actions is not None else ""
            raise ValueError(f"{self.best_npy}: expected {expected}finite floats in [-1, 1], got shape {action.shape} "
                             f"dtype {action.dtype}; the file is not this run's; use --policy last")
        return action

    def best_summary(self) -> dict[str, Any]:
        """``best_params.json`` (validated: an object with an integer ``eval_seed``)."""
        document = self._read_json(self.best_json, "the best policy's evaluation")
        if not isinstance(document, dict) or isinstance(document.get("eval_seed"), bool) \
                or not isinstance(document.get("eval_seed"), int):
            raise ValueError(f"{self.best_json}: expected an object with an integer 'eval_seed'; "
                             "the file is broken; use --policy last")
        return document
