"""Where the benchmarks write: ``runs/benchmarks/`` (untracked) unless ``--save`` asks for the committed
``benchmarks/results/``, so that a casual run never overwrites the published numbers."""

from __future__ import annotations

import argparse
from pathlib import Path

__all__ = ["COMMITTED", "add_save_argument", "results_dir"]

COMMITTED = Path(__file__).resolve().parent / "results"
SCRATCH = Path(__file__).resolve().parent.parent / "runs" / "benchmarks"


def add_save_argument(parser: argparse.ArgumentParser) -> None:
    """``--save``: write the committed results in ``benchmarks/results/``."""
    parser.add_argument("--save", action="store_true",
                        help=f"write the committed results in {COMMITTED} (default: {SCRATCH}, untracked)")


def results_dir(save: bool) -> Path:
    """The output folder (created)."""
    folder = COMMITTED if save else SCRATCH
    folder.mkdir(parents=True, exist_ok=True)
    return folder
