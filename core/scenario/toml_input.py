"""Reading TOML from users (scenario files, study files, ``--set`` values) with a nesting limit.

:func:`read_file` reads a scenario or study file: a regular file, or a pipe (so that a shell's
process substitution ``<(...)`` works), of at most :data:`MAX_FILE_MB`; a device (``/dev/zero``),
a socket or a larger file is refused naming the path, before (or, for a pipe, while) it is read.
A leading UTF-8 byte-order mark is dropped, as the observation readers drop it.

``tomllib`` parses arrays and inline tables recursively, so a value nested a few hundred levels
deep ends in a RecursionError, and one nested a little less passes the parser but then meets
code that walks it recursively (copies, merges, messages). :func:`loads` refuses both with a
:class:`~cistrack.errors.ConfigError` naming the file (or flag) and the limit; syntax errors are
left to the caller (``tomllib.TOMLDecodeError``), which words them for its own input.
"""
from __future__ import annotations

import os
import stat
import sys
import time
from pathlib import Path
from typing import Any

from cistrack.errors import ConfigError
from cistrack.interfaces.reader import not_a_file

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["MAX_DEPTH", "MAX_FILE_MB", "loads", "check_depth", "read_file", "TOMLDecodeError"]

MAX_DEPTH = 16
"""Most levels of tables and arrays inside one another (counting the top level). The deepest
legitimate values are about 5 levels deep (a schedule's phases, a reader's sites)."""

MAX_FILE_MB = 10.0
"""Largest scenario or study file read, MB (10^6 bytes). The built-in ones are under 5 kB; the
limit keeps a wrong path (a log, an archive, a pipe that never ends) from being read whole."""

PIPE_WAIT_TRIES = 10
"""A pipe that gives nothing is read again this many times, 50 ms apart, before it is refused (a
writer may still be opening its end of a named pipe)."""

TOMLDecodeError = tomllib.TOMLDecodeError


def _too_deep(where: str, depth: str) -> ConfigError:
    return ConfigError(f"{where}: tables and arrays are nested {depth} levels deep; at most {MAX_DEPTH} "
                       "levels are allowed")


def check_depth(data: Any, where: str) -> Any:
    """``data`` (tables, arrays, values) if nested at most :data:`MAX_DEPTH` levels; ConfigError
    naming ``where`` otherwise. Walks without recursion, so any depth is measured safely."""
    stack = [(data, 1)]
    while stack:
        value, depth = stack.pop()
        children = value.values() if isinstance(value, dict) else value if isinstance(value, list) else ()
        for child in children:
            if isinstance(child, (dict, list)):
                if depth + 1 > MAX_DEPTH:
                    raise _too_deep(where, f"more than {MAX_DEPTH}")
                stack.append((child, depth + 1))
    return data


def loads(text: str, where: str) -> dict[str, Any]:
    """The TOML document ``text``, checked by :func:`check_depth`; ``where`` names the file or
    flag in errors. Raises ``tomllib.TOMLDecodeError`` for invalid syntax."""
    try:
        data = tomllib.loads(text)
    except RecursionError:
        raise _too_deep(where, "hundreds of") from None
    return check_depth(data, where)


def _too_large(path: Path, size: str) -> ConfigError:
    return ConfigError(f"{path}: larger than the {MAX_FILE_MB:g} MB limit on a scenario or study file ({size}); "
                       "give the path of a scenario or study TOML file")


def _opened(path: Path, pipe: bool):
    """``path`` opened to read bytes; a pipe without waiting for a writer (a named pipe nobody
    writes to would block the open for ever): opened non-blocking, then read blocking, so that a
    writer's data (process substitution) is read whole and no writer reads as empty."""
    if not pipe:
        return open(path, "rb")
    import fcntl

    fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
    fcntl.fcntl(fd, fcntl.F_SETFL, fcntl.fcntl(fd, fcntl.F_GETFL) & ~os.O_NONBLOCK)
    return os.fdopen(fd, "rb")


def read_file(path: Path) -> str:
    """The text of the scenario or study file ``path`` (UTF-8, a leading byte-order mark dropped).
    ConfigError naming the path for what is neither a regular file nor a pipe, for a file larger
    than :data:`MAX_FILE_MB` (a pipe is read up to the limit only), for a pipe that gives nothing
    (a named pipe nobody writes to is not waited for) and for what cannot be read or is not UTF-8."""
    why = not_a_file(path)
    pipe = os.path.exists(path) and stat.S_ISFIFO(os.stat(path).st_mode)
    if why is not None and not pipe:
        raise ConfigError(f"{path}: {why}; give the path of a scenario or study TOML file")
    limit = int(MAX_FILE_MB * 1e6)
    try:
        with _opened(path, pipe) as f:
            size = os.fstat(f.fileno()).st_size
            if size > limit:
                raise _too_large(path, f"{size:,} bytes")
            data = f.read(limit + 1)
            for _ in range(PIPE_WAIT_TRIES if pipe and not data else 0):  # a writer still opening its end
                time.sleep(0.05)
                data = f.read(limit + 1)
                if data:
                    break
    except OSError as exc:
        raise ConfigError(f"{path}: cannot read: {exc.strerror or exc}") from None
    if pipe and not data:
        raise ConfigError(f"{path}: a pipe that nothing was written to (a named pipe without a writer is read as empty); "
                          "give the path of a scenario or study TOML file")
    if len(data) > limit:
        raise _too_large(path, f"more than {limit:,} bytes read")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{path}: cannot read: not UTF-8 text ({exc})") from None
