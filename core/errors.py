"""Exceptions raised by cistrack.

Every error a user can trigger names what was wrong (file, table, key, plugin) and what is
allowed, so that no one has to read a traceback from deep inside numpy.
"""
from __future__ import annotations


class CistrackError(Exception):
    """Base class of every error cistrack raises on purpose."""


class ParameterError(CistrackError, ValueError):
    """A component parameter has the wrong type or an inadmissible value."""


class ConfigError(CistrackError, ValueError):
    """A scenario or study file is unreadable or invalid."""


class UnknownComponentError(CistrackError, KeyError):
    """No component of the requested kind is registered under that name."""

    def __str__(self) -> str:  # KeyError quotes its message; keep it readable
        return str(self.args[0]) if self.args else ""


class DuplicateComponentError(CistrackError):
    """Two plugins registered a component of the same kind under the same name."""


class MeasurementError(CistrackError, ValueError):
    """Measurements are missing, inconsistent or malformed."""


class IODError(CistrackError, RuntimeError):
    """Initial orbit determination could not produce the requested cloud."""


class FilterError(CistrackError, RuntimeError):
    """A filter reached a state it cannot continue from (custody cannot be represented)."""


class StateError(CistrackError, ValueError):
    """States or times given to a dynamics model are malformed (shape, NaN, direction)."""


class PropagationError(CistrackError, RuntimeError):
    """The integrator could not reach the requested time (step limit or step-size underflow)."""


class RunInterrupted(KeyboardInterrupt):
    """A signal (SIGTERM, SIGHUP) asked the process to stop; raised where it arrives so that the
    run ends like a Ctrl-C: completed steps merged, manifest "interrupted" with the signal."""


class PluginError(CistrackError):
    """A plugin's hook or metric stage broke its contract during a run: it raised, called
    ``sys.exit``, or returned what the hook does not promise. The message names the plugin (or
    stage) and the hook; the run ends "failed" with it (not "filter-failed": the filter is not at
    fault)."""


def exception_text(exc: BaseException) -> str:
    """``RuntimeError: boom`` (the type alone when the message is empty); for ``sys.exit`` what was
    called: ``SystemExit: it called sys.exit(3)``."""
    if isinstance(exc, SystemExit):
        return f"SystemExit: it called sys.exit({exc.code!r})"
    return f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__
