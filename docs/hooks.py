"""MkDocs hooks of the documentation site (``hooks:`` in ``mkdocs.yml``).

* The installed package maps three folders onto one import name (``rdmp_gym/`` is ``rdmp_gym``, ``envs/`` is
  ``rdmp_gym.envs``, ``agents/`` is ``rdmp_gym.agents``; see ``setup.py``). The API reference reads the
  sources without importing them, so this module lays the same tree out as links under ``build/api-src/``
  (an ignored folder), the path ``mkdocs.yml`` gives mkdocstrings.
* The benchmark figures committed under ``benchmarks/results/`` become files of the site, served as
  ``results/<name>.png``: a page links ``results/agents.png``, and ``--strict`` fails on a figure that is no
  longer written.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from mkdocs.structure.files import File, Files

ROOT = Path(__file__).resolve().parent.parent
API_SOURCES = ROOT / "build" / "api-src"
SUBPACKAGES = {"envs": ROOT / "envs", "agents": ROOT / "agents"}


def _lay_out_package() -> None:
    """``build/api-src/rdmp_gym/``: links to every entry of ``rdmp_gym/`` plus ``envs`` and ``agents``."""
    package = API_SOURCES / "rdmp_gym"
    if API_SOURCES.exists():
        shutil.rmtree(API_SOURCES)
    package.mkdir(parents=True)
    for entry in (ROOT / "rdmp_gym").iterdir():
        if entry.name != "__pycache__":
            (package / entry.name).symlink_to(entry)
    for name, folder in SUBPACKAGES.items():
        (package / name).symlink_to(folder, target_is_directory=True)


def on_startup(command: str, dirty: bool) -> None:
    _lay_out_package()


def on_files(files: Files, config) -> Files:
    benchmarks = ROOT / "benchmarks"
    for figure in sorted((benchmarks / "results").glob("*.png")):
        files.append(File(f"results/{figure.name}", str(benchmarks), config["site_dir"], config["use_directory_urls"]))
    return files
