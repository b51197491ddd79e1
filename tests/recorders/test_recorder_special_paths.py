"""The rerun recorder refuses, as it is built, a path that is a pipe or a device: from Python a
recording to a named pipe had hung the run (opening it to write waits for a reader) and one to
/dev/full had run the whole scenario to fail at its end (the command line refused both already)."""
from __future__ import annotations

import os

import pytest

from cistrack.errors import ParameterError
from cistrack.plugin.registry import default_registry


def test_a_named_pipe_as_the_recording_path_is_refused_as_the_recorder_is_built(tmp_path):
    fifo = tmp_path / "run.rrd"
    os.mkfifo(fifo)
    with pytest.raises(ParameterError, match="parameter 'path'.*is a named pipe, not a regular file"):
        default_registry().create("recorder", "rerun", path=str(fifo), overwrite=True)


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="no /dev/full here")
def test_a_device_as_the_recording_path_is_refused_as_the_recorder_is_built():
    with pytest.raises(ParameterError, match="is a character device, not a regular file"):
        default_registry().create("recorder", "rerun", path="/dev/full", overwrite=True)


def test_a_directory_or_a_new_file_is_taken(tmp_path):
    reg = default_registry()
    assert reg.create("recorder", "rerun", path=str(tmp_path)).path == str(tmp_path)
    assert reg.create("recorder", "rerun", path=str(tmp_path / "new.rrd")).path == str(tmp_path / "new.rrd")
