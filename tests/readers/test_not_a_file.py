"""What `cistrack fit` and the readers say of a path that is no observation file: each is named
for what it is (a device, a pipe, standard input, a loop of links), never as missing, and none is
opened."""
from __future__ import annotations

import os

import pytest

from cistrack.cli.main import main
from cistrack.errors import MeasurementError
from cistrack.interfaces.reader import not_a_file
from cistrack.runs.observation_files import read_observations


def _said(argv_path: str, tmp_path, capsys) -> str:
    assert main(["fit", argv_path, "--out", str(tmp_path / "fit"), "--quiet"]) == 2
    assert not (tmp_path / "fit").exists()
    return capsys.readouterr().err


@pytest.mark.parametrize("device", ["/dev/zero", "/dev/null"])
def test_a_device_is_said_not_to_be_a_regular_file(device, tmp_path, capsys):
    assert f"observation file {device}: is not a regular file: a character device" in _said(device, tmp_path, capsys)


def test_a_named_pipe_is_said_to_be_one_and_is_not_opened(tmp_path, capsys):
    fifo = tmp_path / "obs.psv"
    os.mkfifo(fifo)
    assert f"observation file {fifo}: is not a regular file: a named pipe (fifo)" in _said(str(fifo), tmp_path, capsys)


def test_a_dash_says_standard_input_is_not_read(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert "observation file -: standard input is not read: give the name of an observation file" in \
        _said("-", tmp_path, capsys)


def test_a_loop_of_symbolic_links_is_said_to_be_one(tmp_path, capsys):
    loop = tmp_path / "loop.psv"
    loop.symlink_to(loop)
    assert f"observation file {loop}: is a loop of symbolic links" in _said(str(loop), tmp_path, capsys)


def test_a_link_to_a_missing_file_names_its_target(tmp_path, capsys):
    link = tmp_path / "link.psv"
    link.symlink_to(tmp_path / "gone.psv")
    err = _said(str(link), tmp_path, capsys)
    assert f"observation file {link}: is a symbolic link to a missing file ({tmp_path / 'gone.psv'})" in err


def test_a_missing_file_is_still_said_to_be_missing(tmp_path, capsys):
    assert "observation file nothing.psv: no such file" in _said("nothing.psv", tmp_path, capsys)


def test_a_link_to_a_regular_file_is_a_file(tmp_path):
    (tmp_path / "obs.psv").write_text("x\n")
    (tmp_path / "link.psv").symlink_to(tmp_path / "obs.psv")
    assert not_a_file(tmp_path / "link.psv") is None


def test_the_readers_refuse_a_pipe_without_opening_it(tmp_path):
    fifo = tmp_path / "obs.psv"
    os.mkfifo(fifo)  # opening it would wait for a writer for ever
    with pytest.raises(MeasurementError, match=r"obs\.psv: is not a regular file: a named pipe"):
        read_observations(fifo, "2026-03-01T00:00:00Z")
