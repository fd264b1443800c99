"""Every ```python block of README.md and docs/*.md runs, so the documentation cannot drift from the code.

The blocks of one page run in page order in one namespace (a later block may use an earlier block's names),
in a fresh working directory per page. A block whose first line starts with ``SKIP_MARK`` is not run (the
reader sees the mark and its reason: a run of minutes); such blocks are counted and must stay few.
Command lines ``rdmp-gym ...`` in ```bash blocks are parsed by the command's own parser (not run), so a
renamed or removed flag in the documentation fails here.

The blocks of a page from the one that :data:`SLOW_FROM` names on run in the slow set only (``make test-all``):
training on the full wiping task, the joint fit of 20-period sessions, a filmed episode (10-20 CPU s each, whose
code the default set's unit tests run on smaller cases).
"""

from __future__ import annotations

import os
import re
import shlex
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("**/*.md"))]
SKIP_MARK = "# Not run by the docs tests:"
MAX_SKIPPED = 4
FENCE = re.compile(r"^(?P<indent>[ \t]*)```(?P<lang>[\w-]*)[^\n]*\n(?P<body>.*?)^(?P=indent)```[ \t]*$",
                   re.MULTILINE | re.DOTALL)


def code_blocks(page: Path, language: str) -> list[tuple[int, str]]:
    """``(line number, dedented code)`` of every fenced block in ``language`` on ``page``."""
    text = page.read_text(encoding="utf-8")
    blocks = []
    for match in FENCE.finditer(text):
        if match["lang"] == language:
            line = text.count("\n", 0, match.start()) + 1
            blocks.append((line, textwrap.dedent(match["body"])))
    return blocks


PYTHON_BLOCKS = [(page, line, code) for page in PAGES for line, code in code_blocks(page, "python")]
RUN_BLOCKS = [block for block in PYTHON_BLOCKS if not block[2].lstrip().startswith(SKIP_MARK)]
SLOW_FROM = {"docs/agents.md": 'run = train(config, "runs/cpi2-tiny")',
             "docs/fitting.md": "joint = fit_joint(demo)",
             "docs/your-own-env.md": "filmed.record_episode("}
"""Per page, a line of its first block that runs in the slow set only; that block and the page's later ones do."""


def _block_id(block: tuple[Path, int, str]) -> str:
    return f"{block[0].relative_to(ROOT)}:{block[1]}"


def _first_slow_line(page: Path) -> float:
    """The line of ``page``'s first block in the slow set (:data:`SLOW_FROM`), inf where it has none."""
    marker = SLOW_FROM.get(str(page.relative_to(ROOT)))
    lines = [line for block_page, line, code in RUN_BLOCKS if block_page == page and marker and marker in code]
    return min(lines, default=float("inf"))


def _with_marks(block: tuple[Path, int, str]):
    slow = block[1] >= _first_slow_line(block[0])
    return pytest.param(block, id=_block_id(block), marks=[pytest.mark.slow] if slow else [])


class _PageSession:
    """One page's namespace and working directory; runs its blocks in order, each at most once."""

    def __init__(self, page: Path, workdir: Path):
        self.blocks = [block for block in RUN_BLOCKS if block[0] == page]
        self.workdir = workdir
        self.namespace: dict = {"__name__": f"docs_snippet_{page.stem}"}
        self.done = 0

    def run_through(self, line: int) -> None:
        while self.done < len(self.blocks) and self.blocks[self.done][1] <= line:
            _, at, code = self.blocks[self.done]
            self.done += 1
            exec(compile(code, f"{self.blocks[0][0].name}:{at}", "exec"), self.namespace)


@pytest.fixture(scope="session")
def page_sessions(tmp_path_factory):
    return {}


@pytest.mark.parametrize("block", [_with_marks(block) for block in RUN_BLOCKS])
def test_python_snippet_runs(block, page_sessions, tmp_path_factory, monkeypatch):
    page, line, _ = block
    if page not in page_sessions:
        page_sessions[page] = _PageSession(page, tmp_path_factory.mktemp(page.stem))
    session = page_sessions[page]
    monkeypatch.chdir(session.workdir)
    monkeypatch.setenv("MUJOCO_GL", os.environ.get("MUJOCO_GL", "egl"))
    session.run_through(line)


def test_snippets_found_and_few_skipped():
    """The extraction finds the README's snippets, and skipped blocks carry a reason and stay few."""
    readme = [block for block in RUN_BLOCKS if block[0].name == "README.md"]
    assert len(readme) >= 2, "the README's snippets were not found"
    skipped = [block for block in PYTHON_BLOCKS if block not in RUN_BLOCKS]
    assert len(skipped) <= MAX_SKIPPED, [_block_id(block) for block in skipped]
    for _, _, code in skipped:
        assert len(code.lstrip().splitlines()[0]) > len(SKIP_MARK) + 10, "a skip mark needs its reason"
    for page in SLOW_FROM:                                              # each names a block that runs
        assert _first_slow_line(ROOT / page) < float("inf"), f"{page}: no block holds {SLOW_FROM[page]!r}"


def _command_lines() -> list[tuple[str, str]]:
    lines = []
    for page in PAGES:
        for at, code in code_blocks(page, "bash"):
            for text in code.replace("\\\n", " ").splitlines():
                command = text.split("#")[0].strip()
                command = re.sub(r"^(\w+=\S+\s+)+", "", command)       # RAY_ADDRESS=... rdmp-gym ...
                if command.startswith("rdmp-gym "):
                    lines.append((f"{page.relative_to(ROOT)}:{at}", command))
    return lines


@pytest.mark.parametrize(("where", "command"), _command_lines(), ids=[where for where, _ in _command_lines()])
def test_documented_command_parses(where, command):
    """The documented ``rdmp-gym`` command lines name existing commands and flags with valid values."""
    from rdmp_gym.agents.cli import parse

    try:
        parse(shlex.split(command)[1:])
    except SystemExit as exit_:
        if exit_.code:
            pytest.fail(f"{where}: `{command}` does not parse (exit {exit_.code})")
    except ValueError as error:
        pytest.fail(f"{where}: `{command}` does not make a command: {error}")
