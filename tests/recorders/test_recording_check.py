"""Before the viewer is started: a whole recording passes, one cut short is named, one with nothing
to show is refused. Real rerun recordings, cut with ordinary file operations."""
from __future__ import annotations

import subprocess
import sys

import pytest

from cistrack.errors import CistrackError
from cistrack.plugins.recorders.recording_check import recording_problem

from .test_web_viewer import write_small_recording


def properties_only(path):
    """A whole rerun recording that logged nothing (rerun writes its properties chunk only)."""
    import rerun as rr

    rec = rr.RecordingStream("cistrack-test-nothing")
    rec.save(str(path))
    rec.flush()
    rec.disconnect()
    return path


@pytest.fixture
def whole(tmp_path):
    path = tmp_path / "whole.rrd"
    write_small_recording(path)
    return path


def test_a_whole_recording_has_no_problem(whole):
    assert recording_problem(whole) is None


def test_a_recording_cut_short_is_said_to_be_cut(whole, tmp_path):
    cut = tmp_path / "cut.rrd"
    cut.write_bytes(whole.read_bytes()[: whole.stat().st_size // 2])
    problem = recording_problem(cut)
    assert problem is not None and str(cut) in problem and "cut short" in problem


def test_a_recording_of_properties_only_is_refused(tmp_path):
    path = properties_only(tmp_path / "nothing.rrd")
    with pytest.raises(CistrackError, match="holds no data to show"):
        recording_problem(path)


def test_cistrack_view_refuses_a_recording_with_nothing_to_show_before_any_viewer(tmp_path):
    path = properties_only(tmp_path / "nothing.rrd")
    proc = subprocess.run([sys.executable, "-m", "cistrack.cli", "view", str(path)], capture_output=True,
                          text=True, timeout=60)
    assert proc.returncode == 2 and "holds no data to show" in proc.stderr and "Traceback" not in proc.stderr
    assert "open in a browser" not in proc.stdout
