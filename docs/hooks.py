"""MkDocs hook: the benchmark figures (``benchmarks/results/*.png``) are served under ``assets/``, so the pages
show the committed figures without copies in ``docs/``."""

from __future__ import annotations

from pathlib import Path

from mkdocs.structure.files import File, Files


def on_files(files: Files, config) -> Files:
    """Add every ``benchmarks/results/*.png`` as ``assets/<name>``."""
    results = Path(config["config_file_path"]).parent / "benchmarks" / "results"
    for figure in sorted(results.glob("*.png")):
        files.append(File.generated(config, f"assets/{figure.name}", abs_src_path=str(figure)))
    return files
