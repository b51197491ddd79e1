"""What the CCSDS KVN writers share: epochs, numbers and the lower-triangular covariance."""
from __future__ import annotations

import numpy as np

from cistrack.units import format_utc, parse_utc

__all__ = ["ccsds_epoch", "num", "lower_triangle", "comment_lines", "COV_KEYS"]

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


def comment_lines(meta: dict) -> list[str]:
    """``COMMENT`` lines for the header (after the version line, where CCSDS KVN allows them) from
    ``meta["comments"]``: e.g. the warning that a run was exported although it did not finish.
    Each comment is one line; line breaks in it become spaces."""
    return [f"COMMENT {' '.join(str(c).split())}" for c in meta.get("comments") or []]
