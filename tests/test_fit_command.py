"""``rdmp-gym fit --out``: an output directory that already holds a fit is refused unless ``--overwrite``."""

from pathlib import Path

import pytest
from rdmp_gym.agents.cli import main as cli_main

from rdmp_gym import load_dmp

SMALL = ["--n-periodic", "10", "--n-transient", "10"]


def _fit(out: Path, *flags: str) -> int:
    return cli_main(["fit", *SMALL, "--out", str(out), *flags])


def _contents(folder: Path) -> dict[str, bytes]:
    return {path.name: path.read_bytes() for path in folder.iterdir()}


def test_an_out_holding_a_fit_is_refused_and_left_as_it_was(tmp_path, capsys) -> None:
    out = tmp_path / "fit"
    assert _fit(out) == 0
    (out / "report.json").write_text("{}\n")        # a report beside the DMP, as a --demo fit leaves
    before = _contents(out)
    capsys.readouterr()
    assert _fit(out, "--style", "2") == 2
    error = capsys.readouterr().err
    assert "--out" in error and str(out) in error and "dmp.json" in error and "report.json" in error
    assert "--overwrite" in error
    assert _contents(out) == before


@pytest.mark.parametrize("name", ["dmp-2.json", "fit.png", "report.json"])
def test_any_file_of_a_fit_occupies_the_out(tmp_path, capsys, name: str) -> None:
    out = tmp_path / "fit"
    out.mkdir()
    (out / name).write_text("earlier")
    assert _fit(out) == 2 and name in capsys.readouterr().err
    assert _contents(out) == {name: b"earlier"}


def test_an_empty_or_unrelated_out_is_written(tmp_path) -> None:
    out = tmp_path / "fit"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    assert _fit(out) == 0
    assert load_dmp(out / "dmp.json").n_dims == 3 and (out / "notes.txt").read_text() == "mine"


def test_overwrite_replaces_the_earlier_fit_and_removes_its_leftovers(tmp_path) -> None:
    out = tmp_path / "fit"
    assert _fit(out) == 0
    earlier = (out / "dmp.json").read_bytes()
    for name in ("dmp-3.json", "fit.png", "report.json"):      # an earlier fit's files the new one does not write
        (out / name).write_text("earlier")
    (out / "notes.txt").write_text("mine")
    assert _fit(out, "--style", "2", "--overwrite") == 0
    assert sorted(path.name for path in out.iterdir()) == ["dmp.json", "notes.txt"]
    assert (out / "dmp.json").read_bytes() != earlier and load_dmp(out / "dmp.json").n_dims == 3


def test_a_failed_overwrite_puts_the_earlier_fit_back(tmp_path, capsys) -> None:
    out = tmp_path / "fit"
    assert _fit(out) == 0
    (out / "report.json").write_text("{}\n")
    before = _contents(out)
    assert _fit(out, "--demo", str(tmp_path / "missing.csv"), "--overwrite") == 2
    assert "missing.csv" in capsys.readouterr().err
    assert _contents(out) == before                  # nothing set aside is left behind


def test_an_out_that_is_a_file_is_refused(tmp_path, capsys) -> None:
    out = tmp_path / "fit"
    out.write_text("a file")
    assert _fit(out, "--overwrite") == 2
    assert "--out" in capsys.readouterr().err and out.read_text() == "a file"
