"""Signals that end a run like Ctrl-C, so that its completed steps and manifest are kept.

A SIGTERM (``kill``, a batch scheduler, a container stop) or SIGHUP (a closed terminal) raises
:class:`~cistrack.errors.RunInterrupted` where it arrives; the run then merges its completed
steps and records "interrupted (SIGTERM)" in its manifest, and the CLI exits with 128 + the
signal number. Each interrupt is noted (:mod:`cistrack.interrupts`), so that one lost where it was
raised (inside a ctypes callback) is raised again between the run's steps.
"""
from __future__ import annotations

import contextlib
import signal
import sys
import threading
from collections.abc import Iterator

from cistrack.errors import RunInterrupted
from cistrack.interrupts import clear, ctrl_c_handler, note, raise_pending, take_pending

__all__ = ["install_signal_handlers", "interrupts_prevail"]


def _raise_interrupted(signum, frame) -> None:
    _raise_unless_lost(note(RunInterrupted(signal.Signals(signum).name)), frame)


@ctrl_c_handler
def _raise_ctrl_c(signum, frame) -> None:
    """Ctrl-C as Python raises it (an empty message: "SIGINT, Ctrl-C" in the manifest), but as a
    RunInterrupted, so that code that catches a plugin's own KeyboardInterrupt (the registry,
    loading plugins) still stops for a real one."""
    _raise_unless_lost(note(RunInterrupted()), frame)


def _raise_unless_lost(exc: RunInterrupted, frame) -> None:
    """Raise ``exc`` (noted) unless the signal arrived in a callback that Python would print it from
    as "Exception ignored" and drop: importlib's module-lock callback (a Ctrl-C during a lazy import
    had printed that traceback under the run's progress bar) and llvmlite's (:data:`_C_CALLBACKS`). There it stays noted and is raised
    between the run's steps (:func:`cistrack.interrupts.raise_pending`)."""
    code = getattr(frame, "f_code", None)
    if code is not None and (code.co_name == "cb" and code.co_filename.startswith("<frozen importlib")
                             or _C_CALLBACKS in code.co_filename.replace("\\", "/")):
        return
    raise exc


_C_CALLBACKS = "/llvmlite/binding/"
"""Where llvmlite's ctypes callbacks live (its object cache's notify, while numba compiles): a
Ctrl-C raised there is printed as "Exception ignored" with a traceback (a clean-clone CI, Ctrl-C at
0.6 s), so it too stays noted and is raised between the run's steps."""


def install_signal_handlers() -> dict:
    """SIGTERM and SIGHUP end a run like Ctrl-C (completed steps merged, manifest "interrupted"),
    and Ctrl-C raises a RunInterrupted (where Python's own handler is in place); only in the main
    thread of the process running ``main``. Returns the previous handlers."""
    old = {}
    clear()
    if threading.current_thread() is threading.main_thread():
        for name in ("SIGTERM", "SIGHUP"):
            sig = getattr(signal, name, None)
            if sig is not None:
                old[sig] = signal.signal(sig, _raise_interrupted)
        if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
            old[signal.SIGINT] = signal.signal(signal.SIGINT, _raise_ctrl_c)
    return old


@contextlib.contextmanager
def interrupts_prevail() -> Iterator[None]:
    """Run a command so that an interrupt noted while it ran ends it as that interrupt: an exception
    of any kind it raises meanwhile is the interrupt's doing (a Ctrl-C while numba's C extension
    imports ``numba._devicearray`` comes out as ``ImportError: numba._devicearray failed to import``,
    probe J1), and one noted but never raised (lost in a callback) is raised when it returns. The
    traceback such a C import prints of the RunInterrupted (through :data:`sys.excepthook`) is not
    shown: the command says "interrupted" instead."""
    previous_hook = sys.excepthook

    def hook(kind, value, tb) -> None:
        if not isinstance(value, RunInterrupted):
            previous_hook(kind, value, tb)

    sys.excepthook = hook
    try:
        yield
    except Exception as exc:
        interrupt = take_pending()
        if interrupt is None:
            raise
        raise interrupt from exc
    finally:
        sys.excepthook = previous_hook
    raise_pending()
