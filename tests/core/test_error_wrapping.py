"""An error is wrapped within 120 columns for a person at a terminal and kept on one line for a
log, a pipe or a script; a path longer than the line is never broken."""
from __future__ import annotations

import io

from cistrack.cli.main import error_text
from cistrack.errors import ConfigError


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


LONG = ("--out runs/quick: holds the results of another run (scenario 'quick', seed 2). A run never replaces "
        "the results of another scenario, other settings or another seed: give another --out, remove it, or "
        "add --overwrite to replace them")


def test_an_error_on_a_terminal_is_wrapped_under_its_label_within_120_columns():
    lines = error_text(ConfigError(LONG), _Terminal()).splitlines()
    assert len(lines) > 1 and lines[0].startswith("cistrack: error: --out runs/quick:")
    assert all(len(line) <= 120 for line in lines)
    assert all(line.startswith(" " * len("cistrack: ")) for line in lines[1:])  # under the label
    assert " ".join(" ".join(lines).split()) == f"cistrack: error: {LONG}"


def test_an_error_to_a_pipe_or_file_stays_on_one_line():
    assert error_text(ConfigError(LONG), io.StringIO()) == f"cistrack: error: {LONG}"


def test_a_path_longer_than_the_line_is_not_broken():
    path = "/tmp/" + "x" * 150 + "/fit.json"
    text = error_text(ConfigError(f"{path}: not a fit record"), _Terminal())
    assert f"{path}:" in text.split()
