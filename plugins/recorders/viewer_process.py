"""The rerun viewer as a separate process: finding its executable, checking for a display,
starting it on 127.0.0.1 and waiting until it (not another process) listens, and tying a child's
life to ours (:func:`parent_death_preexec`)."""
from __future__ import annotations

import ctypes
import ctypes.util
import importlib.util
import os
import signal
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path

from cistrack.errors import CistrackError

from .ports import LOOPBACK, listened_by

__all__ = ["LOOPBACK", "ViewerUnavailableError", "find_viewer_executable", "check_viewer",
           "parent_death_preexec", "start_viewer", "wait_for_port"]

_PR_SET_PDEATHSIG = 1  # linux/prctl.h


class ViewerUnavailableError(CistrackError, RuntimeError):
    """The native rerun viewer cannot be started here (no executable, or no display)."""


def find_viewer_executable() -> str | None:
    """Path of the native rerun viewer binary (the ``rerun-cli`` one shipped with rerun-sdk, or
    ``rerun`` on PATH), or None."""
    spec = importlib.util.find_spec("rerun_cli")
    if spec is not None and spec.submodule_search_locations:
        for loc in spec.submodule_search_locations:
            exe = Path(loc) / ("rerun.exe" if os.name == "nt" else "rerun")
            if exe.is_file() and os.access(exe, os.X_OK):
                return str(exe)
    return shutil.which("rerun")


def parent_death_preexec():
    """A ``preexec_fn`` for :class:`subprocess.Popen` that has Linux kill the child (SIGKILL) when
    the process starting it dies, however it dies (``kill -9`` included), so that a child server
    never outlives us holding its port; None where the system has no such request (not Linux).

    The request is ``prctl(PR_SET_PDEATHSIG, SIGKILL)``, made in the child between fork and exec
    (it survives the exec). Linux sends the signal when the *thread* that started the child ends,
    so start such children from a thread that lives as long as they should (the main thread).
    A parent that died before the request was made is noticed (the child's parent id changed)
    and the child exits at once."""
    if not sys.platform.startswith("linux"):
        return None
    libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
    prctl = libc.prctl  # looked up here: the child only calls it
    parent = os.getpid()

    def arm() -> None:
        if prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) != 0 or os.getppid() != parent:
            os._exit(1)

    return arm


def _has_display() -> bool:
    if not sys.platform.startswith("linux"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def wait_for_port(port: int, proc: subprocess.Popen, timeout_s: float) -> bool:
    """True once ``proc`` listens on 127.0.0.1:``port``; False if it exits or ``timeout_s`` passes.

    A connection that another process answers does not count (where the system tells the
    listener's process: :func:`.ports.listened_by`): a viewer that cannot bind a busy port exits,
    and this returns False instead of sending the user to the other process."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            return False
        with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
            s.settimeout(0.2)
            answered = s.connect_ex((LOOPBACK, port)) == 0
        if answered and listened_by(port, proc.pid) is not False:
            return True
        time.sleep(0.05)
    return False


def check_viewer() -> str:
    """The viewer executable, or :class:`ViewerUnavailableError` saying what to do instead."""
    exe = find_viewer_executable()
    if exe is None:
        raise ViewerUnavailableError(
            "cannot start the rerun viewer: no 'rerun' executable found (it ships with "
            "rerun-sdk as rerun-cli). Write a recording with --rerun out.rrd instead and open "
            "it where a viewer is installed: `rerun out.rrd`.")
    if not _has_display():
        raise ViewerUnavailableError(
            "cannot start the native rerun viewer: this machine has no display (DISPLAY and "
            "WAYLAND_DISPLAY are unset). Use --rerun out.rrd and open it elsewhere with "
            "`rerun --bind 127.0.0.1 out.rrd` (or in a browser: `rerun --web-viewer --bind 127.0.0.1 "
            "out.rrd`), or use --rerun-serve and connect a viewer to the printed URL.")
    return exe


def start_viewer(port: int, timeout_s: float = 15.0) -> subprocess.Popen:
    """Start the native viewer listening on 127.0.0.1:``port``; the process once it listens."""
    exe = check_viewer()
    proc = subprocess.Popen(
        [exe, "--bind", LOOPBACK, "--port", str(port), "--expect-data-soon"],
        stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
        start_new_session=True, env={**os.environ, "RERUN_APP_ONLY": "true"})
    if not wait_for_port(port, proc, timeout_s=timeout_s):
        err = ""
        if proc.poll() is not None and proc.stderr is not None:
            err = proc.stderr.read().decode(errors="replace").strip()[-800:]
        raise ViewerUnavailableError(
            f"the rerun viewer ({exe}) did not start listening on {LOOPBACK}:{port}"
            + (f": {err}" if err else "") + ". Use --rerun out.rrd and open the file instead.")
    return proc
