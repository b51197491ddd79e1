"""Shared rules for user-facing values: seeds, names that become paths, ports, and memory needs.

The same rule applies whether a value comes from a scenario or study file or from a command-line
flag; each check raises :class:`~cistrack.errors.ConfigError` naming where the value came from
(``where``: a file and key, or a flag) and what is allowed.
"""
from __future__ import annotations

import math
import numbers
import os
from typing import Any

from cistrack.errors import ConfigError, invisible_character, quoted
from cistrack.interfaces.limits import PORT_MAX, PORT_MIN, check_port  # defined where components reach them

__all__ = ["SEED_MAX", "PORT_MIN", "PORT_MAX", "check_seed", "check_path_component", "check_count",
           "check_port", "available_memory_bytes", "check_memory", "format_bytes"]

SEED_MAX = 2 ** 63 - 1
"""Largest seed: seeds are stored as signed 64-bit integers (manifests, step tables)."""


def check_seed(value: Any, where: str) -> int:
    """``value`` as a seed: an integer in [0, 2**63 - 1]."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ConfigError(f"{where}: seed {quoted(value)} must be an integer from 0 to 2**63-1")
    if not 0 <= value <= SEED_MAX:
        raise ConfigError(f"{where}: seed {value} is out of range: allowed 0 to 2**63-1 ({SEED_MAX})")
    return int(value)


def check_count(value: Any, where: str, minimum: int = 1, maximum: int | None = None) -> int:
    """``value`` as an integer count in [minimum, maximum]."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ConfigError(f"{where}: {quoted(value)} must be an integer >= {minimum}"
                          + (f" and <= {maximum}" if maximum is not None else ""))
    if value < minimum or (maximum is not None and value > maximum):
        raise ConfigError(f"{where}: {value} is out of range: allowed {minimum} to "
                          f"{maximum if maximum is not None else 'any larger integer'}")
    return int(value)


#: The rule of :func:`check_path_component`, as its messages state it.
PATH_COMPONENT_RULE = ("no '/', '\\', control or invisible characters; not '.' or '..'; not starting with '.', '-' "
                       "or a space, nor ending with a space; at most 100 characters")


def check_path_component(value: Any, where: str) -> str:
    """``value`` as a name that becomes one directory or file name (a run id, a label).

    Refused: non-strings, empty, ``.`` and ``..``, leading or trailing spaces, a leading ``.`` or
    ``-``, path separators, and control or invisible formatting characters (bidirectional
    overrides, zero-width characters); at most 100 characters."""
    if not isinstance(value, str):
        raise ConfigError(f"{where}: {quoted(value)} must be a string")
    bad = ""
    if value in ("", ".", ".."):
        bad = "is empty or a relative directory"
    elif len(value) > 100:
        bad = "is longer than 100 characters"
    elif "/" in value or "\\" in value or (os.altsep and os.altsep in value):
        bad = "contains a path separator"
    elif value.startswith((".", "-")) or value != value.strip():
        bad = "starts with '.' or '-' or has leading/trailing spaces"
    elif invisible_character(value):
        bad = (f"contains a control or invisible formatting character ({invisible_character(value)}; control "
               "characters, bidirectional overrides and zero-width characters are refused)")
    if bad:
        raise ConfigError(f"{where}: {quoted(value)} {bad}; it names a directory, so it must be one path component "
                          f"({PATH_COMPONENT_RULE})")
    return value


def available_memory_bytes() -> int | None:
    """Memory available to a new allocation (Linux MemAvailable, else free physical pages); None
    if unknown."""
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return None


def format_bytes(n: float) -> str:
    """``n`` bytes in B, KiB, MiB, GiB, TiB, PiB (three significant digits)."""
    if not math.isfinite(n):
        return "an unbounded amount"
    units = ("B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB")
    i = 0
    while n >= 1024 and i < len(units) - 1:
        n /= 1024.0
        i += 1
    return f"{n:.3g} {units[i]}"


def check_memory(need_bytes: float, where: str, what: str) -> None:
    """Refuse before allocating when ``need_bytes`` exceeds the available memory.

    ``where`` names the key or flag, ``what`` says what needs the memory."""
    avail = available_memory_bytes()
    if avail is None:
        return
    if need_bytes > avail:
        raise ConfigError(f"{where}: {what} needs about {format_bytes(need_bytes)} of memory, but only "
                          f"{format_bytes(avail)} is available; reduce it")
