"""A named pipe given where a scenario, study or recording file is expected is refused at once,
naming it: opening one waits for its other end for ever (a run had printed nothing for minutes).
A pipe with a writer (a shell's process substitution) is still read."""
from __future__ import annotations

import os
import threading
from pathlib import Path

from cistrack.cli.main import main
from cistrack.scenario.builtin_scenarios import builtin_scenario_path


def _fifo(tmp_path: Path, name: str) -> Path:
    p = tmp_path / name
    os.mkfifo(p)
    return p


def test_a_scenario_path_that_is_a_named_pipe_nobody_writes_to_is_refused(tmp_path, capsys):
    fifo = _fifo(tmp_path, "s.toml")
    assert main(["run", str(fifo)]) == 2
    assert f"{fifo}: a pipe that nothing was written to" in capsys.readouterr().err


def test_a_study_path_that_is_a_named_pipe_nobody_writes_to_is_refused(tmp_path, capsys):
    fifo = _fifo(tmp_path, "study.toml")
    assert main(["study", "run", str(fifo), "--out", str(tmp_path / "st")]) == 2
    assert f"{fifo}: a pipe that nothing was written to" in capsys.readouterr().err


def test_a_named_pipe_whose_writer_comes_a_moment_later_is_read(tmp_path):
    from cistrack.scenario.toml_input import read_file

    fifo = _fifo(tmp_path, "s.toml")
    text = Path(builtin_scenario_path("quick")).read_text()

    def write():
        with open(fifo, "w") as fh:
            fh.write(text)

    writer = threading.Timer(0.1, write)
    writer.start()
    try:
        assert read_file(fifo) == text
    finally:
        writer.join()


def test_a_recording_path_that_is_a_named_pipe_is_refused_before_the_run(tmp_path, capsys):
    fifo = _fifo(tmp_path, "run.rrd")
    assert main(["run", "quick", "--out", str(tmp_path / "r"), "--rerun", str(fifo), "--quiet"]) == 2
    err = " ".join(capsys.readouterr().err.split())
    assert f"--rerun {fifo}: is not a regular file: a named pipe (fifo)" in err
    assert not (tmp_path / "r").exists()


def test_a_recording_path_that_is_a_device_is_refused_before_the_run(tmp_path, capsys):
    assert main(["run", "quick", "--out", str(tmp_path / "r"), "--rerun", "/dev/full", "--overwrite", "--quiet"]) == 2
    assert "--rerun /dev/full: is not a regular file: a character device" in " ".join(capsys.readouterr().err.split())
