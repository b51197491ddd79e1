"""The status of a run directory as it is now, not only as its manifest last said.

A run writes ``status = "running"`` and its process (host name and process id) into the manifest
when it starts, and its final status when it ends. A process killed with SIGKILL (or lost with its
machine) never writes the end, so its manifest stays "running"; :func:`run_status` reads such a
manifest as ``"interrupted"`` with the reason "process gone" when the recorded process no longer
exists on this host. A run recorded on another host (a Dask worker) cannot be checked from here
and reads as its manifest says. A reused process id reads as still running (the safe direction).
"""
from __future__ import annotations

import os
import socket
from pathlib import Path

from cistrack.results.store import read_manifest

__all__ = ["run_status", "process_gone", "RUN_STATUSES"]

RUN_STATUSES: tuple[str, ...] = ("running", "finished", "filter-failed", "failed", "interrupted")
"""The statuses a run writes into its manifest."""


def process_gone(process: dict | None) -> bool:
    """Whether the process recorded in a manifest (``{"host", "pid"}``) is known to no longer
    exist: it ran on this host and no process has its id now."""
    if not isinstance(process, dict) or process.get("host") != socket.gethostname():
        return False
    pid = process.get("pid")
    if isinstance(pid, bool) or not isinstance(pid, int) or pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except OSError:  # it exists but belongs to another user
        return False
    return False


def run_status(directory: str | Path) -> tuple[str, str]:
    """(status, reason) of the run in ``directory``: the manifest's, except that a run left
    "running" by a process that is gone is ("interrupted", "interrupted (process gone: ...)")."""
    man = read_manifest(directory)
    status = str(man.get("status", "unknown"))
    summary = man.get("summary")
    reason = str(summary.get("failure", "") or "") if isinstance(summary, dict) else ""
    proc = man.get("process")
    if status == "running" and process_gone(proc):
        return "interrupted", (f"interrupted (process gone: pid {proc['pid']} on {proc['host']} ended without "
                               f"finishing the run; the steps it completed stay readable)")
    return status, reason
