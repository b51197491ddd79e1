"""Ending the ``cistrack`` process after a run without Python's interpreter teardown.

After a run, Python's finalization (clearing some 1,500 modules and deallocating numba's typing
and lowering registries, which numba builds on its first compiled call) takes about 0.5 s of
wall time on a loaded 2-core machine: measured with ``benchmarks/process_timeline.py`` and by
timing main()'s return to the process's end (0.53-0.70 s; 0.02 s with ``os._exit``). That is
a sixth of Example 1's whole process and does nothing a finished command needs.

So the command line's entry point (:func:`cistrack.cli.main.console_main`) ends a process this way
only when the command said it may (:func:`allow_quick_exit`, called by ``cistrack run`` once
every observer has finished and the results are written and closed, and never for a run with
a rerun recorder, whose SDK flushes its recording from its own exit handlers). It then does
what finalization would have done that matters: it flushes stdout and stderr, shuts logging
down and runs every ``atexit`` handler (a third-party observer may flush files there), and
ends the process with :func:`os._exit` and main()'s exit status. If flushing fails (a closed
pipe, a full disk), or a thread Python would wait for is still alive (other than the idle
propagation workers), it exits the ordinary way, so those cases behave exactly as before.
``CISTRACK_FULL_EXIT=1`` always exits the ordinary way. Called in-process (tests calling
:func:`cistrack.cli.main`) nothing of this happens.
"""
from __future__ import annotations

import atexit
import logging
import os
import sys
import threading

from cistrack.env_flags import env_flag
from cistrack.errors import CistrackError

__all__ = ["allow_quick_exit", "exit_process"]

_ALLOWED = False


def _full_exit_asked() -> bool:
    """``$CISTRACK_FULL_EXIT`` (:func:`cistrack.env_flags.env_flag`); a value that is not yes or no
    gets the ordinary exit, the safe one, and a warning."""
    try:
        return bool(env_flag("CISTRACK_FULL_EXIT"))
    except CistrackError as exc:
        if sys.stderr is not None:
            print(f"cistrack: warning: {exc}; exiting the ordinary way", file=sys.stderr)
        return True


def allow_quick_exit() -> None:
    """Declare that the command has finished its work and may skip interpreter teardown."""
    global _ALLOWED
    _ALLOWED = True


def _busy_threads() -> bool:
    """Whether a thread that Python would wait for at exit may still be working: any non-daemon
    thread but the main one and the propagation pool's idle workers (``cistrack-propagate``)."""
    main = threading.main_thread()
    return any(t is not main and t.is_alive() and not t.daemon and not t.name.startswith("cistrack-propagate")
               for t in threading.enumerate())


def exit_process(code: int) -> None:
    """End the process with ``code``: quickly if the command allowed it, else through sys.exit."""
    if not _ALLOWED or _full_exit_asked() or _busy_threads():
        sys.exit(code)
    try:
        for stream in (sys.stdout, sys.stderr):
            if stream is not None:
                stream.flush()
    except (OSError, ValueError):  # a closed pipe or full disk: let Python report it as it always did
        sys.exit(code)
    logging.shutdown()
    run_exit_handlers = getattr(atexit, "_run_exitfuncs", None)
    if run_exit_handlers is None:  # pragma: no cover (CPython has it; other interpreters: no shortcut)
        sys.exit(code)
    run_exit_handlers()
    try:
        for stream in (sys.stdout, sys.stderr):
            if stream is not None:
                stream.flush()
    except (OSError, ValueError):
        sys.exit(code)
    os._exit(code)
