"""Paths the operating system refuses (here a file name longer than a file system allows) end in
one line naming the path and the reason, exit status 2, never a traceback."""
from __future__ import annotations

from pathlib import Path

import pytest

from cistrack.cli.main import main

LONG = "y" * 300  # longer than the 255 bytes a file name may have
SHIPPED = str(Path(__file__).parents[2] / "core" / "scenarios" / "real_data" / "observations.psv")


@pytest.mark.parametrize("argv", [
    ["run", LONG + ".toml"],
    ["fit", LONG + ".psv"],
    ["export", LONG, "--format", "oem"],
    ["view", LONG + ".rrd"],
    ["fit", SHIPPED, "--out", LONG],
])
def test_a_file_name_too_long_is_refused_in_one_line(tmp_path, monkeypatch, capsys, argv):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err
    last = err.strip().splitlines()[-1]
    assert last.startswith("cistrack: error: ") and LONG in last and "Traceback" not in err


def test_a_fit_from_a_deleted_current_folder_says_the_folder_is_gone_and_names_it(tmp_path, monkeypatch, capsys):
    """It had said only "No such file or directory" (probe J7)."""
    gone = tmp_path / "gone"
    gone.mkdir()
    monkeypatch.chdir(gone)
    gone.rmdir()
    assert main(["fit", SHIPPED, "--quiet"]) == 2
    last = capsys.readouterr().err.strip().splitlines()[-1]
    assert last.startswith(f"cistrack: error: the current folder {gone} no longer exists (it was deleted)")
    assert "cd to an existing folder, or give absolute paths" in last
