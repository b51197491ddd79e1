"""Reading an .rrd back with rerun's own reader (rerun.chunk.RrdReader, rerun-sdk 0.41).

The file's chunks are turned into one row per logged event of an entity: the time of that row
on every timeline, and each component column as a numpy array.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pyarrow as pa
from rerun.chunk import RrdReader

_CONTROL = "rerun.controls.RowId"


@dataclass
class EntityRow:
    """One logged row of an entity: timeline name -> int, component column -> value."""

    times: dict[str, int]
    components: dict[str, object]
    row_id: bytes


def read_entities(path: str | Path) -> dict[str, list[EntityRow]]:
    """Every row of the first recording in ``path``, grouped by entity path ("/world/particles"),
    each list ordered by row id (the order in which rows were logged)."""
    reader = RrdReader(str(path))
    out: dict[str, list[EntityRow]] = {}
    for chunk in reader.stream():
        batch = chunk.to_record_batch()
        timelines = set(chunk.timeline_names)
        cols = {}
        for name, col in zip(batch.schema.names, batch.columns):
            if pa.types.is_timestamp(col.type) or pa.types.is_duration(col.type):
                col = col.cast(pa.int64())
            cols[name] = col.to_pylist()
        for i in range(chunk.num_rows):
            times = {t: cols[t][i] for t in timelines if cols[t][i] is not None}
            comps = {n: v[i] for n, v in cols.items() if n not in timelines and n != _CONTROL}
            out.setdefault(chunk.entity_path, []).append(EntityRow(times, comps, cols[_CONTROL][i]))
    for rows in out.values():
        rows.sort(key=lambda r: r.row_id)  # row ids are time-ordered (TUIDs)
    return out


def component(row: EntityRow, name: str) -> np.ndarray:
    """A component column of a row as a float array ("Points3D:positions" -> (N, 3))."""
    return np.asarray(row.components[name], dtype=float)


def last_per_step(rows: list[EntityRow]) -> dict[int, EntityRow]:
    """The last row logged at each value of the ``step`` timeline (what the viewer shows there)."""
    out: dict[int, EntityRow] = {}
    for r in rows:
        if "step" in r.times:
            out[int(r.times["step"])] = r
    return out
