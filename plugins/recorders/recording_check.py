"""Whether a rerun recording file can be shown whole, read before a viewer is started for it.

A recording cistrack finished writing ends with rerun's footer (its table of contents). A file
without one was cut short (a run killed, a disk that filled, a copy stopped part-way) or written
by an older rerun: the viewer shows what it can read before the cut. A whole file that holds no
chunk of data (only the recording's properties) shows nothing and is refused.
"""
from __future__ import annotations

import warnings
from pathlib import Path

from cistrack.errors import CistrackError

__all__ = ["recording_problem"]


def recording_problem(rrd: str | Path) -> str | None:
    """None for a whole recording; else a sentence saying what is wrong with ``rrd`` and what a
    viewer will show. Raises :class:`~cistrack.errors.CistrackError` for a whole file that holds no
    chunk, or one rerun cannot open."""
    from rerun.chunk import RrdReader

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            reader = RrdReader(str(rrd))
        except Exception as exc:
            raise CistrackError(f"{rrd}: not a readable rerun recording ({_first_line(exc)})") from None
    if any("footer" in str(w.message) for w in caught):
        return (f"{rrd}: the recording was cut short: it has no end marker (a run stopped while writing "
                "it, a disk that filled, a copy stopped part-way); the viewer shows what it can read "
                "before the cut, which may be nothing")
    try:
        empty = not any(not str(c.entity_path).startswith("/__properties") for c in reader.stream())
    except Exception as exc:
        raise CistrackError(f"{rrd}: not a readable rerun recording ({_first_line(exc)})") from None
    if empty:
        raise CistrackError(f"{rrd}: the recording holds no data to show; write it again with "
                            "'cistrack run --rerun FILE.rrd'")
    return None


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[0] if text else type(exc).__name__
