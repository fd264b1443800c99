"""Every ``python`` code block of the README and of the documentation pages runs, so the docs cannot drift from
the code. The blocks of one page run in order in one namespace (a later block may use an earlier one's names),
in a temporary working directory."""

import os
import re
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
BLOCK = re.compile(r"^(?P<indent>[ \t]*)```python\n(?P<code>.*?)^(?P=indent)```", re.S | re.M)


def python_blocks(path: Path) -> list[str]:
    """The ``python`` fenced blocks of a Markdown file, dedented (blocks may sit inside list items)."""
    return [textwrap.dedent(match.group("code")) for match in BLOCK.finditer(path.read_text())]


def test_the_pages_have_snippets():
    counts = {path.name: len(python_blocks(path)) for path in PAGES}
    assert counts["README.md"] >= 2 and sum(counts.values()) >= 10, counts


@pytest.mark.parametrize("page", [p for p in PAGES if python_blocks(p)], ids=lambda p: p.name)
def test_every_snippet_runs(page, tmp_path, monkeypatch):
    os.environ.setdefault("MUJOCO_GL", "egl")
    monkeypatch.chdir(tmp_path)
    (tmp_path / "runs" / "docs").mkdir(parents=True)
    namespace: dict = {"__name__": "__docs__"}
    for index, code in enumerate(python_blocks(page)):
        try:
            exec(compile(code, f"{page.name}[block {index}]", "exec"), namespace)
        except Exception as error:
            raise AssertionError(f"{page.name}, python block {index} fails:\n{code}") from error
