"""Rows written as they come, in part files of many rows, merged into one table at the end.

A run writes its per-step tables (``steps/``, ``estimates/``) while it runs, so that a killed run
leaves its completed steps readable. One file per step made a 400,000-row measurement file write
400,000 files; :class:`PartWriter` keeps rows in memory and writes one part (atomically: a
temporary file and a rename) once ``rows_per_part`` rows are waiting or ``seconds_per_part``
seconds have passed since the last part, and when the run ends or fails. A killed process loses
at most the rows of the part being filled (at most ``seconds_per_part`` of work); every part
already written stays readable.

Parts are named ``part-<first step, 9 digits>.parquet`` so that their names sort in step order.
"""
from __future__ import annotations

import os
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # pyarrow is imported on use (~35 ms that listing the registry never needs)
    import pyarrow as pa

__all__ = ["PartWriter", "ROWS_PER_PART", "SECONDS_PER_PART", "read_parts", "write_checked", "read_checked"]

ROWS_PER_PART = 1000
"""Rows per part file by default."""
SECONDS_PER_PART = 10.0
"""A part is written at least this often (s of wall time) while rows are waiting."""


class PartWriter:
    """Buffer rows (dicts) and write them to ``directory/part-*.parquet`` in batches.

    Parameters
    ----------
    directory : the folder of the parts (created by :meth:`start`).
    rows_per_part : int >= 1, rows per part file (1: a part per row).
    seconds_per_part : float > 0, longest wait before waiting rows are written.
    """

    def __init__(self, directory: str | Path, rows_per_part: int = ROWS_PER_PART,
                 seconds_per_part: float = SECONDS_PER_PART) -> None:
        if int(rows_per_part) < 1 or not seconds_per_part > 0:
            raise ValueError(f"rows_per_part must be >= 1 and seconds_per_part > 0, got {rows_per_part}, "
                             f"{seconds_per_part}")
        self.directory = Path(directory)
        self.rows_per_part = int(rows_per_part)
        self.seconds_per_part = float(seconds_per_part)
        self._rows: list[dict[str, Any]] = []
        self._first = 0
        self._last_write = time.monotonic()
        self.n_parts = 0

    def start(self) -> None:
        """Create the folder and delete parts an earlier run left there."""
        self.directory.mkdir(parents=True, exist_ok=True)
        for old in list(self.directory.glob("part-*.parquet")) + list(self.directory.glob("part-*.tmp")):
            old.unlink()
        self._rows, self.n_parts, self._last_write = [], 0, time.monotonic()

    def add(self, step_index: int, row: dict[str, Any]) -> None:
        """Queue ``row`` (of step ``step_index``); write a part when enough rows or time gathered."""
        if not self._rows:
            self._first = int(step_index)
        self._rows.append(row)
        if len(self._rows) >= self.rows_per_part or time.monotonic() - self._last_write >= self.seconds_per_part:
            self.flush()

    def flush(self) -> None:
        """Write the waiting rows as one part (nothing when none wait)."""
        if not self._rows:
            return
        rows, self._rows = self._rows, []
        final = self.directory / f"part-{self._first:09d}.parquet"
        tmp = final.with_suffix(".tmp")
        try:
            write_checked(_table(rows), tmp)
            os.replace(tmp, final)
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise
        self.n_parts += 1
        self._last_write = time.monotonic()

    def parts(self) -> list[Path]:
        """The part files written, in step order."""
        return sorted(self.directory.glob("part-*.parquet"))


def _table(rows: list[dict[str, Any]]) -> pa.Table:
    """Rows as a table with the union of their keys, in order of first appearance (a key missing
    from a row is null there), as if each row had been a part of its own and the parts merged."""
    from cistrack.results.arrow_rows import table_from_rows  # from_pydict's table, without importing pandas

    return table_from_rows(rows)


def read_parts(directory: str | Path) -> pa.Table | None:
    """The rows of every part in ``directory``, in step order (None when there is none)."""
    parts = sorted(Path(directory).glob("part-*.parquet"))
    if not parts:
        return None
    import pyarrow as pa

    return pa.concat_tables([read_checked(p) for p in parts], promote_options="default")


def write_checked(table: pa.Table, path: str | Path) -> None:
    """Write ``table`` as Parquet with a checksum on every page, so that a flipped bit is found on
    reading (:func:`read_checked`) rather than read as another number."""
    import pyarrow.parquet as pq

    pq.write_table(table, path, write_page_checksum=True)


def read_checked(path: str | Path) -> pa.Table:
    """The Parquet table at ``path``, its page checksums verified (where it was written with them):
    pyarrow raises ArrowException (OSError) for a page whose bytes changed."""
    import pyarrow.parquet as pq

    # ParquetFile.read: pq.read_table imports pyarrow.dataset (~0.1 s) for a plain file
    return pq.ParquetFile(path, page_checksum_verification=True).read()
