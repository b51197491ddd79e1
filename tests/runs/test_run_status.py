"""A manifest left "running" by a process that is gone reads as interrupted (issue 17: SIGKILL)."""
from __future__ import annotations

import json
import os
import socket
import subprocess
import sys

from cistrack.results.run_status import process_gone, run_status
from cistrack.studies.resume import run_state


def _manifest(d, **kw):
    d.mkdir(parents=True, exist_ok=True)
    (d / "manifest.json").write_text(json.dumps({"status": "running", **kw}))
    return d


def _gone_pid() -> int:
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()  # reaped: no process has this id now (until the system reuses it)
    return p.pid


def test_a_running_manifest_whose_process_is_gone_reads_as_interrupted(tmp_path):
    d = _manifest(tmp_path / "r", process={"host": socket.gethostname(), "pid": _gone_pid()})
    status, reason = run_status(d)
    assert status == "interrupted" and "process gone" in reason
    assert run_state(str(d)) == "gone"  # a study says so and runs it again


def test_a_running_manifest_of_a_live_process_stays_running(tmp_path):
    d = _manifest(tmp_path / "r", process={"host": socket.gethostname(), "pid": os.getpid()})
    assert run_status(d) == ("running", "") and run_state(str(d)) == "todo"


def test_a_process_on_another_host_cannot_be_checked_and_stays_running(tmp_path):
    d = _manifest(tmp_path / "r", process={"host": socket.gethostname() + "-elsewhere", "pid": _gone_pid()})
    assert run_status(d)[0] == "running"


def test_an_old_manifest_without_a_process_stays_as_it_was(tmp_path):
    assert run_status(_manifest(tmp_path / "r"))[0] == "running"
    assert not process_gone(None) and not process_gone({"host": socket.gethostname(), "pid": "12"})
