"""Interrupts that could not stop the program where they arrived, raised again where it can stop.

:func:`exit_interrupted_while_starting` ends the command when a Ctrl-C comes before any handler
exists (while its first modules load). A signal handler raises where Python happens to be. Inside a ctypes callback (numba's compiler
calls back into Python through llvmlite while it writes its object cache) an exception is printed
as "ignored" and lost, and a Ctrl-C there let a run finish and exit 0. The handlers
(:mod:`cistrack.cli.signals`) :func:`note` each interrupt they raise; the run calls
:func:`raise_pending` between its steps, which raises one that was lost.
"""
from __future__ import annotations

import os
import signal
import sys
from collections.abc import Callable

from cistrack.errors import RunInterrupted

__all__ = ["note", "raise_pending", "take_pending", "clear", "exit_interrupted_while_starting", "interrupt_text",
           "ctrl_c_handler", "from_signal", "plugin_fault"]

_PENDING: list[RunInterrupted] = []
_CTRL_C_HANDLERS: list[Callable] = []


def ctrl_c_handler(handler: Callable) -> Callable:
    """Mark ``handler`` (returned as it is) as a SIGINT handler that raises a RunInterrupted for a
    Ctrl-C: while it is installed, a plain KeyboardInterrupt comes from code, not from a signal."""
    _CTRL_C_HANDLERS.append(handler)
    return handler


def from_signal(exc: BaseException) -> bool:
    """Whether ``exc`` is an interrupt a signal raised: a RunInterrupted (the command's handlers),
    or a KeyboardInterrupt where Python's own Ctrl-C handler is in place (the API), which cannot be
    told from one that code raised. A KeyboardInterrupt raised while the command's Ctrl-C handler is
    installed is code's own (a plugin's ``raise KeyboardInterrupt``), not a signal."""
    if isinstance(exc, RunInterrupted):
        return True
    if not isinstance(exc, KeyboardInterrupt):
        return False
    return signal.getsignal(signal.SIGINT) not in _CTRL_C_HANDLERS


def plugin_fault(exc: BaseException) -> bool:
    """Whether ``exc``, raised from a plugin's code, is that plugin's failure (named, the run
    "failed", never a traceback): every exception, BaseExceptions such as SystemExit, GeneratorExit
    and a KeyboardInterrupt no signal raised included; only an interrupt from a signal
    (:func:`from_signal`) stops the command as an interrupt (probe I1)."""
    return not from_signal(exc)


def note(exc: RunInterrupted) -> RunInterrupted:
    """Remember ``exc`` (about to be raised by a signal handler); returns it."""
    _PENDING.append(exc)
    return exc


def raise_pending() -> None:
    """Raise the interrupt noted last, if any (once: the record is cleared)."""
    if _PENDING:
        exc = _PENDING[-1]
        _PENDING.clear()
        raise exc


def take_pending() -> RunInterrupted | None:
    """The interrupt noted last, or None; the record is cleared."""
    exc = _PENDING[-1] if _PENDING else None
    _PENDING.clear()
    return exc


def interrupt_text(exc: BaseException) -> str:
    """How a run's summary and manifest record the interrupt ``exc``: ``interrupted (SIGTERM)``, or
    ``interrupted (SIGINT, Ctrl-C)`` for a Ctrl-C (whose exception has no message)."""
    return f"interrupted ({exc})" if str(exc) else "interrupted (SIGINT, Ctrl-C)"


def clear() -> None:
    """Forget the interrupts noted so far (a new command starts, or one was handled)."""
    _PENDING.clear()


def exit_interrupted_while_starting() -> None:
    """End the ``cistrack`` command interrupted before its handlers exist: one line, status 130
    (``os._exit``, not SystemExit: under ``python -m`` the interpreter turned that into a death by
    SIGINT)."""
    sys.stderr.write("cistrack: interrupted (SIGINT) while starting; nothing was done\n")
    sys.stderr.flush()
    os._exit(130)
