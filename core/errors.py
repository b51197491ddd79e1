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
    """Initial orbit determination could not produce the requested cloud.

    ``settings``: the IOD's own parameters that the message's advice names (``lower
    min_fit/order``), by those names; a caller whose user sets them otherwise than as the
    scenario's ``[iod]`` keys (``cistrack fit``: ``--set iod.NAME=VALUE``) adds how."""

    def __init__(self, *args: object, settings: tuple[str, ...] = ()) -> None:
        super().__init__(*args)
        self.settings = tuple(settings)


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


QUOTED_CHARACTERS = 40
"""Most characters of a value a message quotes (:func:`quoted`)."""


def quoted(value: object) -> str:
    """``value`` as a message quotes it: its repr, or, when that is longer than
    :data:`QUOTED_CHARACTERS` + 20 characters (a 100,000-character ``--set`` value), the start of
    it and its length, e.g. ``'xxxxxxxx...' (100,000 characters)``, so that no message grows
    with what it quotes."""
    text = repr(value)
    if len(text) <= QUOTED_CHARACTERS + 20:
        return text
    if isinstance(value, str):
        return f"{value[:QUOTED_CHARACTERS] + '...'!r} ({len(value):,} characters)"
    return f"{text[:QUOTED_CHARACTERS]}... ({len(text):,} characters as written)"


def clipped(name: str) -> str:
    """``name`` (a designation, as a file gives it) as a message shows it: whole, or, when longer than
    :data:`QUOTED_CHARACTERS` + 20 characters, its start, its last 10 characters and its length, e.g.
    ``AAAA...AAAB (100,000 characters)``, so that no message or progress line grows with it (probe L10)
    and two names that differ only near their end still read apart (probe M10)."""
    if len(name) <= QUOTED_CHARACTERS + 20:
        return name
    return f"{name[:QUOTED_CHARACTERS - 10]}...{name[-10:]} ({len(name):,} characters)"


UNPRINTABLE_CATEGORIES = frozenset({"Cc", "Cf", "Cs", "Co", "Cn", "Zl", "Zp"})
"""Unicode categories refused in names and labels: control, format (bidirectional overrides and
isolates, zero-width characters), surrogate, private-use and unassigned characters, line and
paragraph separators. They would make a name that reads differently from what it is, or turn a
terminal's line around."""


def invisible_character(text: str) -> str | None:
    """The first character of ``text`` in :data:`UNPRINTABLE_CATEGORIES`, as ``U+202E``; None when
    it has none."""
    import unicodedata

    return next((f"U+{ord(c):04X}" for c in text if unicodedata.category(c) in UNPRINTABLE_CATEGORIES), None)


def shown(text: str) -> str:
    """``text`` as a message shows an argument it names unquoted (``--site 568``): as it is when
    short and printable, else quoted (control characters escaped, so that none acts on the
    terminal) and shortened as :func:`quoted` does."""
    text = str(text)
    return text if len(text) <= QUOTED_CHARACTERS + 20 and text.isprintable() else quoted(text)
