"""Progress lines of a long least squares, for whoever watches it (``cistrack fit`` prints them).

A fit of tens of thousands of observations takes minutes, and each iteration propagates to every
observation time: 66,000 observations had left ``cistrack fit`` silent for 201 s. Within
:func:`reported_to`, a least squares over at least :data:`PROGRESS_ROWS` observations says each
accepted iteration and each pass of outlier rejection, and a line of variations each point (it had
left the same file silent for 90 s more); smaller ones, which take seconds, say nothing more.
"""
from __future__ import annotations

from contextlib import contextmanager
from contextvars import ContextVar
from typing import Callable, Iterator

__all__ = ["PROGRESS_ROWS", "reported_to", "tell"]

PROGRESS_ROWS = 5000
"""A least squares over at least this many observations says its iterations."""

_REPORT: ContextVar[Callable[[str], None] | None] = ContextVar("cistrack_least_squares_progress", default=None)


@contextmanager
def reported_to(report: Callable[[str], None] | None) -> Iterator[None]:
    """Within it, long least squares in this thread say their progress to ``report`` (None: nothing)."""
    token = _REPORT.set(report)
    try:
        yield
    finally:
        _REPORT.reset(token)


def tell(rows: int, text: str) -> None:
    """``text`` to the current report when a least squares of ``rows`` observations is a long one."""
    report = _REPORT.get()
    if report is not None and rows >= PROGRESS_ROWS:
        report(text)
