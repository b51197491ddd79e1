"""`cistrack view` killed with SIGKILL takes its web viewer child with it: the port is free again.

A real ``cistrack view`` process serves a real recording; once it has printed its URL it is
killed with SIGKILL (no handler, no clean-up runs), and the rerun process it started must end and
leave the port free for the next ``cistrack view``.
"""
from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import psutil
import pytest

from cistrack.plugins.recorders.viewer_process import find_viewer_executable, parent_death_preexec

from .test_web_viewer import free_port, write_small_recording

CLI = Path(sys.executable).with_name("cistrack")

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="parent-death signal is Linux's")


def _port_free(port: int) -> bool:
    with socket.socket() as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            s.bind(("127.0.0.1", port))
        except OSError:
            return False
    return True


def _wait(condition, timeout_s: float) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(0.1)
    return condition()


def test_kill_9_of_cistrack_view_frees_the_viewer_port(tmp_path):
    if find_viewer_executable() is None or not CLI.exists():
        pytest.skip("the rerun viewer executable or the cistrack command is not installed")
    rrd = tmp_path / "run.rrd"
    write_small_recording(rrd)
    port = free_port()
    view = subprocess.Popen([str(CLI), "view", str(rrd), "--port", str(port)], stdout=subprocess.PIPE,
                            stderr=subprocess.DEVNULL, text=True)
    children: list[psutil.Process] = []
    try:
        assert "open in a browser" in view.stdout.readline()
        children = psutil.Process(view.pid).children(recursive=True)
        assert children and not _port_free(port)
        os.kill(view.pid, signal.SIGKILL)
        view.wait(timeout=10)
        assert _wait(lambda: not any(c.is_running() and c.status() != psutil.STATUS_ZOMBIE for c in children), 15.0)
        assert _wait(lambda: _port_free(port), 15.0)
    finally:
        view.kill()
        for c in children:  # a viewer left behind (by a build without the fix) is not left running
            try:
                c.kill()
            except psutil.NoSuchProcess:
                pass


def test_a_child_started_with_the_preexec_dies_with_its_parent():
    """A sleeping grandchild started through the preexec by a process that is then SIGKILLed."""
    code = ("import subprocess, sys, time\n"
            "from cistrack.plugins.recorders.viewer_process import parent_death_preexec\n"
            "p = subprocess.Popen(['sleep', '300'], preexec_fn=parent_death_preexec())\n"
            "print(p.pid, flush=True)\n"
            "time.sleep(300)\n")
    parent = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    child = None
    try:
        child = psutil.Process(int(parent.stdout.readline()))
        parent.kill()
        parent.wait(timeout=10)
        assert _wait(lambda: not child.is_running() or child.status() == psutil.STATUS_ZOMBIE, 10.0)
    finally:
        parent.kill()
        if child is not None and child.is_running():
            child.kill()


def test_the_preexec_is_none_where_the_system_has_no_parent_death_signal(monkeypatch):
    monkeypatch.setattr(sys, "platform", "darwin")
    assert parent_death_preexec() is None
