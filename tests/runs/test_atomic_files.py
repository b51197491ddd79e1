"""Files written whole or not at all: a failed write leaves no temporary file and its error names
the file being written."""
from __future__ import annotations

import subprocess
import sys

import pytest

from cistrack.results.atomic_files import write_text_atomic


def test_a_write_that_fails_names_the_file_and_leaves_nothing_behind(tmp_path):
    target = tmp_path / "fit.json"
    code = ("import resource, signal, sys\n"
            "from cistrack.results.atomic_files import write_text_atomic\n"
            "signal.signal(signal.SIGXFSZ, signal.SIG_IGN)\n"
            "resource.setrlimit(resource.RLIMIT_FSIZE, (10, 10))  # the disk as good as full: writes fail\n"
            "try:\n"
            f"    write_text_atomic({str(target)!r}, 'x' * 1000)\n"
            "except OSError as exc:\n"
            "    print(exc.filename)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.stdout.strip() == str(target), out.stderr
    assert list(tmp_path.iterdir()) == []


def test_taking_a_run_directorys_lock_removes_what_a_killed_writer_left_half_written(tmp_path):
    from cistrack.results.dir_lock import run_lock

    (tmp_path / ".manifest.json.1a2b3c4d.tmp").write_text('{"status": "fin')  # kill -9 during a write
    (tmp_path / "notes.tmp").write_text("a user's file")
    with run_lock(tmp_path):
        pass
    assert sorted(p.name for p in tmp_path.iterdir()) == [".run.lock", "notes.tmp"]


@pytest.mark.parametrize("length", [240, 244, 250, 255])
def test_a_target_whose_name_the_file_system_takes_is_written_whatever_its_length(tmp_path, length):
    """Its temporary name beside it had been 14 characters longer: names of 242 to 255 characters
    were refused with "File name too long" (probe J8)."""
    target = tmp_path / ("e" * (length - 4) + ".oem")
    write_text_atomic(target, "data")
    assert target.read_text() == "data" and sorted(p.name for p in tmp_path.iterdir()) == [target.name]


def test_the_shortened_temporary_name_of_a_long_unicode_name_is_whole_characters(tmp_path):
    target = tmp_path / ("é" * 120 + ".oem")  # 244 bytes in UTF-8
    write_text_atomic(target, "data")
    assert target.read_text() == "data"
