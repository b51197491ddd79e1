"""A scenario or study path is read only when it is a file of data of a sane size, as UTF-8 text
(a leading byte-order mark dropped); anything else is refused naming the path, before it is read."""
from __future__ import annotations

import os
import threading

import pytest

from cistrack.errors import ConfigError
from cistrack.scenario import toml_input
from cistrack.scenario.loading import load_scenario
from cistrack.studies.study_file import load_study


def _quick_text() -> str:
    return open(load_scenario("quick").source, encoding="utf-8").read()


@pytest.mark.parametrize("load", [load_scenario, load_study])
def test_a_character_device_is_refused_without_being_read(load):
    with pytest.raises(ConfigError, match=r"/dev/zero: is not a regular file: a character device"):
        load("/dev/zero")


@pytest.mark.parametrize("load", [load_scenario, load_study])
def test_a_file_above_the_size_limit_is_refused_naming_it_and_the_limit(tmp_path, monkeypatch, load):
    monkeypatch.setattr(toml_input, "MAX_FILE_MB", 0.001)
    path = tmp_path / "big.toml"
    path.write_text("# " + "x" * 2000 + "\n")
    with pytest.raises(ConfigError, match=rf"{path}: larger than the 0.001 MB limit .*\(2,003 bytes\)"):
        load(str(path))


def test_a_pipe_is_read_as_a_process_substitution_gives_it(tmp_path):
    fifo = tmp_path / "scenario.fifo"
    os.mkfifo(fifo)
    writer = threading.Thread(target=lambda: fifo.write_text(_quick_text()))
    writer.start()
    assert load_scenario(str(fifo)).name == "quick"
    writer.join()


def test_a_pipe_is_read_only_up_to_the_size_limit(tmp_path, monkeypatch):
    monkeypatch.setattr(toml_input, "MAX_FILE_MB", 0.001)
    fifo = tmp_path / "endless.fifo"
    os.mkfifo(fifo)

    def write():
        try:
            with open(fifo, "w") as f:
                f.write("#" * 100_000)
        except BrokenPipeError:
            pass
    writer = threading.Thread(target=write)
    writer.start()
    with pytest.raises(ConfigError, match=r"larger than the 0.001 MB limit .*more than 1,000 bytes read"):
        load_scenario(str(fifo))
    writer.join()


def test_a_scenario_file_with_a_utf8_byte_order_mark_is_read(tmp_path):
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf" + _quick_text().encode())
    assert load_scenario(str(path)).raw == load_scenario("quick").raw


def test_a_scenario_read_from_a_pipe_finds_its_relative_measurement_file_in_the_current_directory(tmp_path,
                                                                                                   monkeypatch):
    """``cistrack run <(cat real-data.toml)``: its relative [measurements] file had been looked for
    under /proc/PID/fd, which never holds it."""
    text = open(load_scenario("real-data").source, encoding="utf-8").read()
    (tmp_path / "real_data").mkdir()
    monkeypatch.chdir(tmp_path)
    r, w = os.pipe()
    os.write(w, text.encode())
    os.close(w)
    try:
        scen = load_scenario(f"/dev/fd/{r}")
    finally:
        os.close(r)
    assert scen.measurements_file == (tmp_path / "real_data" / "observations.psv").resolve()
