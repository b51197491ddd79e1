"""An --out whose path leaves no room for the results' own files under the system's limit on a
path's length is refused before anything is made or run (it had been made, the IOD run, and its
first record refused by the system, a half-made directory left behind)."""
from __future__ import annotations

import os

import pytest

from cistrack.errors import ConfigError
from cistrack.results.output_paths import INSIDE_PATH_BYTES, check_output_dir


def _deep(tmp_path, total: int) -> str:
    parts, path = [], os.path.abspath(tmp_path)
    while len(path) + 201 < total:
        parts.append("e" * 200)
        path = os.path.join(path, parts[-1])
    return path + "/" + "f" * (total - len(path) - 1)


def test_an_out_too_long_for_its_files_is_refused_and_nothing_is_made(tmp_path):
    limit = os.pathconf(tmp_path, "PC_PATH_MAX")
    out = _deep(tmp_path, limit - INSIDE_PATH_BYTES + 10)
    with pytest.raises(ConfigError, match=r"the path is \d+ bytes long, and the results' own files inside it would "
                                          rf"pass the system's limit of {limit} bytes a path; give a shorter path"):
        check_output_dir(out, "--out")
    assert list(tmp_path.iterdir()) == []


def test_an_out_with_room_for_its_files_is_made(tmp_path):
    limit = os.pathconf(tmp_path, "PC_PATH_MAX")
    out = _deep(tmp_path, limit - INSIDE_PATH_BYTES - 10)
    assert os.path.isdir(check_output_dir(out, "--out"))
