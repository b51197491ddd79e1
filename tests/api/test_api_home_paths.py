"""A path given to the Python API that starts with ``~`` means the home folder, as it does on the
command line (where the shell expands it): ``out=Path("~/x")`` had made a folder literally named
``~`` in the current directory while the message read as the home folder."""
from __future__ import annotations

from pathlib import Path

import pytest

import cistrack as ct


@pytest.fixture
def home(tmp_path, monkeypatch) -> Path:
    from cistrack.propagation.kernels import kernel_cache_dir

    monkeypatch.setenv("CISTRACK_KERNEL_DIR", str(kernel_cache_dir().resolve()))  # the compiled kernels stay where they are
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    (tmp_path / "home").mkdir()
    (tmp_path / "cwd").mkdir()
    monkeypatch.chdir(tmp_path / "cwd")
    return tmp_path / "home"


@pytest.mark.parametrize("out", ["~/r", Path("~/r")])
def test_a_run_into_a_home_path_writes_there_and_makes_no_folder_named_tilde(home, out):
    run = ct.run("quick", settings={"duration_days": 1.4}, out=out)
    assert run.directory == home / "r" and (home / "r" / "manifest.json").is_file()
    assert not Path("~").exists()


def test_a_run_read_back_from_a_home_path_is_found(home):
    ct.run("quick", settings={"duration_days": 1.4}, out=home / "r")
    assert ct.read_run("~/r").status == "finished"
