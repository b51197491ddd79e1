"""Reading TOML from users (scenario files, study files, ``--set`` values) with a nesting limit.

``tomllib`` parses arrays and inline tables recursively, so a value nested a few hundred levels
deep ends in a RecursionError, and one nested a little less passes the parser but then meets
code that walks it recursively (copies, merges, messages). :func:`loads` refuses both with a
:class:`~cistrack.errors.ConfigError` naming the file (or flag) and the limit; syntax errors are
left to the caller (``tomllib.TOMLDecodeError``), which words them for its own input.
"""
from __future__ import annotations

import sys
from typing import Any

from cistrack.errors import ConfigError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["MAX_DEPTH", "loads", "check_depth", "TOMLDecodeError"]

MAX_DEPTH = 16
"""Most levels of tables and arrays inside one another (counting the top level). The deepest
legitimate values are about 5 levels deep (a schedule's phases, a reader's sites)."""

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
