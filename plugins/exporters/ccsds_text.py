"""What the CCSDS KVN writers share: epochs, numbers and the lower-triangular covariance."""
from __future__ import annotations

import textwrap

import numpy as np

from cistrack.errors import ConfigError
from cistrack.units import format_utc, parse_utc

__all__ = ["ccsds_epoch", "num", "lower_triangle", "comment", "comment_lines", "kvn_text", "COV_KEYS", "MAX_LINE"]

MAX_LINE = 254
"""The longest line of a KVN message, characters (CCSDS 502.0-B-3, section 7.4.1: 254 characters)."""

_AXES = ("X", "Y", "Z", "X_DOT", "Y_DOT", "Z_DOT")
COV_KEYS = [f"C{_AXES[i]}_{_AXES[j]}" for i in range(6) for j in range(i + 1)]
"""OPM covariance keywords in the order of the lower triangle (CX_X, CY_X, CY_Y, ...)."""


def ccsds_epoch(utc: str) -> str:
    """ISO UTC text -> CCSDS 'YYYY-MM-DDThh:mm:ss.ffffff' (no zone letter)."""
    return format_utc(parse_utc(utc))[:-1]


def num(x: float) -> str:
    """Shortest text that reads back as the same double."""
    return repr(float(x))


def lower_triangle(c: np.ndarray) -> list[list[float]]:
    """Rows of the lower triangle of a (6, 6) matrix (1, 2, ..., 6 values)."""
    return [[float(c[i, j]) for j in range(i + 1)] for i in range(6)]


def comment(text) -> list[str]:
    """``text`` as ``COMMENT`` lines of at most :data:`MAX_LINE` characters, wrapped at spaces (a
    word longer than a line is cut); line breaks in it become spaces."""
    width = MAX_LINE - len("COMMENT ")
    parts = textwrap.wrap(" ".join(str(text).split()), width, break_on_hyphens=False)
    return [f"COMMENT {p}" for p in parts] or ["COMMENT"]


def comment_lines(meta: dict) -> list[str]:
    """``COMMENT`` lines for the header (after the version line, where CCSDS KVN allows them) from
    ``meta["comments"]``: e.g. the warning that a run was exported although it did not finish.
    Each comment is wrapped by :func:`comment`."""
    return [line for c in meta.get("comments") or [] for line in comment(c)]


def kvn_text(exporter: str, lines: list[str]) -> str:
    """The file's text; ConfigError naming the keyword when a line is longer than :data:`MAX_LINE`
    (a value such as OBJECT_NAME too long for the format: refused, not cut short, as a shortened
    name would no longer identify the object). A CCSDS KVN message is ASCII: any other character (a
    designation such as "δρο") is written as its Python escape (``\u03b4``), which reads back to it."""
    lines = [line.encode("ascii", "backslashreplace").decode("ascii") for line in lines]
    for line in lines:
        if len(line) > MAX_LINE:
            key, _, value = line.partition(" = ")
            shown = value if len(value) <= 40 else value[:37] + "..."
            raise ConfigError(f"exporter '{exporter}': {key} {shown!r} has {len(value)} characters; a CCSDS KVN line "
                              f"holds at most {MAX_LINE} characters, so {key} at most {MAX_LINE - len(key) - 3}: "
                              "give the object a shorter name")
    return "\n".join(lines) + "\n"
