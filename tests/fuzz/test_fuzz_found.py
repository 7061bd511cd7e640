"""Inputs the fuzz suite (``test_fuzz_readers.py``) found failing, kept as plain tests with
the exact input; each states what the CLI must now do."""

from __future__ import annotations

import shutil
from pathlib import Path

from pkm_pin.cli import main

DATA = Path(__file__).resolve().parents[1] / "data"


def one_error_line(capsys) -> str:
    """The single ``pkm-pin: error:`` line of the last command."""
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("pkm-pin: error: "), lines
    return lines[0]


def test_an_analysis_error_names_the_file(tmp_path, capsys):
    """Gepetto's kangaroo_like folder (unchanged) whose loop does not close within the
    joint limits: the error line names the URDF, not only the loop (found on the corpus
    file itself: 'pkm-pin: error: loop ... does not close' said nothing of which file)."""
    folder = tmp_path / "kangaroo"
    shutil.copytree(DATA / "gepetto" / "kangaroo_like", folder)
    assert main(["analyze", str(folder / "robot.urdf"), "--json"]) == 2
    line = one_error_line(capsys)
    assert line.startswith(f"pkm-pin: error: {folder / 'robot.urdf'}: loop ")
    assert "does not close" in line


def test_a_reader_error_is_not_named_twice(tmp_path, capsys):
    """A reader error already naming the file keeps its own wording (no second prefix)."""
    path = tmp_path / "m.toml"
    path.write_text("name = 1\n")
    assert main(["analyze", str(path), "--json"]) == 2
    line = one_error_line(capsys)
    assert line.count("m.toml") == 1


def test_a_line_separator_in_a_file_name_stays_on_one_line(tmp_path, capsys):
    """A file whose name holds U+2028 (a line break for ``splitlines``, as for a terminal
    log reader) is named in an error line that stays one line."""
    path = tmp_path / "m\u2028x.toml"
    path.write_text("name = 1\n")
    assert main(["analyze", str(path), "--json"]) == 2
    assert "x.toml" in one_error_line(capsys)
