"""cistrack view --port: invalid ports are refused by the option parser, and a port another process
listens on is refused before any URL is printed, so the URL never opens another process's viewer.

The busy ports are real listening sockets on 127.0.0.1 (this test process, or a real second
viewer); the command runs through its real entry point.
"""
from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys

import pytest

from cistrack.errors import CistrackError, ConfigError
from cistrack.plugins.recorders.viewer_process import find_viewer_executable, wait_for_port
from cistrack.plugins.recorders.web_viewer import serve_recording

from .test_web_viewer import free_port, write_small_recording

needs_viewer = pytest.mark.skipif(find_viewer_executable() is None,
                                  reason="the rerun viewer executable is not installed")


@pytest.fixture(scope="module")
def rrd(tmp_path_factory):
    path = tmp_path_factory.mktemp("port") / "run.rrd"
    write_small_recording(path)
    return path


@pytest.fixture
def listener():
    """A socket of this process listening on a port of 127.0.0.1 (another process, to cistrack)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        s.listen(8)
        yield s.getsockname()[1]


def run_view(rrd, port: str) -> tuple[int, str, str]:
    """``cistrack view RRD --port PORT`` as a process: (exit status, first line of its output,
    its error output). A process that prints a URL is stopped there: it would serve until Ctrl-C."""
    proc = subprocess.Popen([sys.executable, "-m", "cistrack.cli", "view", str(rrd), f"--port={port}"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        first_line = proc.stdout.readline()  # "" once the process has ended without printing
        if "http" in first_line:
            os.killpg(proc.pid, signal.SIGKILL)  # the command and the viewer it started
        err = proc.communicate(timeout=120)[1]
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
    return proc.returncode, first_line, err


def assert_refused_naming_the_option(rrd, port: str) -> None:
    code, first_line, err = run_view(rrd, port)
    assert "http" not in first_line, f"--port {port!r} served: {first_line}"
    assert code == 2, err
    assert "--port" in err and "1 to 65535" in err and "Traceback" not in err


@pytest.mark.parametrize("port", ["0", "65536", "70000", "-1", "99999999999999999999"])
def test_a_port_outside_1_to_65535_is_refused_naming_the_option(rrd, port):
    assert_refused_naming_the_option(rrd, port)


@pytest.mark.parametrize("port", ["abc", "9090.5", "1_000", "", " 9090", "9e3", "\u0669\u0660\u0669\u0660"])
def test_a_port_that_is_not_a_whole_number_is_refused_naming_the_option(rrd, port):
    assert_refused_naming_the_option(rrd, port)


def test_serving_refuses_a_port_out_of_range_before_starting_anything(rrd):
    with pytest.raises(ConfigError, match=r"--port.*1 to 65535"):
        serve_recording(rrd, web_port=70000)


def test_a_busy_port_is_refused_before_a_url_is_printed(rrd, listener):
    code, first_line, err = run_view(rrd, str(listener))
    assert "http" not in first_line, f"printed a URL for a busy port: {first_line}"
    assert code == 2, err
    assert f"--port {listener}" in err and "in use" in err and "Traceback" not in err
    assert "choose another port, e.g. --port " in err


@needs_viewer
def test_a_port_held_by_another_viewer_is_refused(rrd):
    with serve_recording(rrd, web_port=free_port()) as first:
        with pytest.raises(CistrackError, match=rf"--port {first.web_port}.*in use"):
            second = serve_recording(rrd, web_port=first.web_port)
            second.close()


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the listener's process is known from /proc")
def test_a_listener_of_another_process_is_not_taken_for_the_started_one(listener):
    """What a viewer does when its port is taken: it fails to bind and exits. Waiting for it must
    not mistake the port's holder for it."""
    bind_and_exit = ("import socket, sys\n"
                     "s = socket.socket()\n"
                     f"try:\n    s.bind(('127.0.0.1', {listener})); s.listen(1)\n"
                     "except OSError:\n    sys.exit(1)\n")
    proc = subprocess.Popen([sys.executable, "-c", bind_and_exit])
    try:
        assert wait_for_port(listener, proc, timeout_s=120) is False
    finally:
        proc.kill()
        proc.wait()
