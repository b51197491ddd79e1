"""What a recording's default blueprint was built from, carried in the recording itself.

The recorder sends it as the recording property :data:`PROPERTY` (a JSON text), so that
``cistrack view`` can build the same blueprint again for another viewer (one that renders in
software and plays slower, :mod:`.web_viewer`) from the .rrd file alone, without the run.
The system view's camera depends only on the box around its points, so the box is kept, not the
points.
"""
from __future__ import annotations

import json
import math
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cistrack.lazy import LazyModule

from .blueprint import default_blueprint, points_box

rr = LazyModule("rerun")

__all__ = ["BlueprintInputs", "PROPERTY", "SCAN_CHUNKS", "read_blueprint_inputs"]

PROPERTY = "cistrack_blueprint"
"""The recording property (entity ``/__properties/cistrack_blueprint``) holding the inputs."""

_VERSION = 1

SCAN_CHUNKS = 64
"""How many of a recording's first chunks are searched for the property: the recorder flushes it
with the recording's other properties before any step is logged, so a large recording is not
read whole to find it."""


def _pair(value) -> tuple[float, float] | None:
    if value is None:
        return None
    a, b = (float(v) for v in value)
    return (a, b) if math.isfinite(a) and math.isfinite(b) else None


@dataclass(frozen=True)
class BlueprintInputs:
    """The arguments of :func:`.blueprint.default_blueprint` a recording was opened with.

    ``system_box_km``: (2, 3) the corners (min, max) of the points the system view frames, or
    None; ``utc_range_s``: the run's first and last ``utc`` time, unix seconds, or None;
    ``watching``, ``burns``: as for :func:`.blueprint.default_blueprint`."""

    system_box_km: np.ndarray | None
    utc_range_s: tuple[float, float] | None
    watching: bool
    burns: bool

    @classmethod
    def of(cls, system_km: np.ndarray | None, utc_range_s: tuple[float, float] | None,
           watching: bool, burns: bool) -> "BlueprintInputs":
        """The inputs of a run whose system view frames ``system_km`` (N, 3), km."""
        return cls(points_box(system_km), _pair(utc_range_s), bool(watching), bool(burns))

    def blueprint(self, live: bool = False, frame_s: float | None = None):
        """The default blueprint for a viewer drawing a frame every ``frame_s`` seconds."""
        return default_blueprint(self.system_box_km, self.utc_range_s, live=live, watching=self.watching,
                                 burns=self.burns, frame_s=frame_s)

    def to_json(self) -> str:
        box = None if self.system_box_km is None else np.asarray(self.system_box_km).tolist()
        return json.dumps({"version": _VERSION, "system_box_km": box,
                           "utc_range_s": None if self.utc_range_s is None else list(self.utc_range_s),
                           "watching": self.watching, "burns": self.burns})

    @classmethod
    def from_json(cls, text: str) -> "BlueprintInputs | None":
        """The inputs in ``text``; None when it is not a version this code reads."""
        try:
            d = json.loads(text)
            if not isinstance(d, dict) or d.get("version") != _VERSION:
                return None
            box = d.get("system_box_km")
            box = None if box is None else np.asarray(box, dtype=float).reshape(2, 3)
            if box is not None and not np.all(np.isfinite(box)):
                box = None
            return cls(box, _pair(d.get("utc_range_s")), bool(d.get("watching")), bool(d.get("burns")))
        except (ValueError, TypeError):
            return None

    def send(self, rec) -> None:
        """Send the inputs to the recording ``rec`` as its property :data:`PROPERTY`."""
        rec.send_property(PROPERTY, rr.AnyValues(inputs=self.to_json()))


def read_blueprint_inputs(rrd: str | Path) -> BlueprintInputs | None:
    """The inputs the recording ``rrd`` carries among its first :data:`SCAN_CHUNKS` chunks; None
    when it carries none (a recording written by another program or an older cistrack) or cannot
    be read."""
    from rerun.chunk import RrdReader

    entity = f"/__properties/{PROPERTY}"
    try:
        with warnings.catch_warnings():  # a file without rerun's footer is read whole, with a warning
            warnings.simplefilter("ignore")
            reader = RrdReader(str(rrd))
        for i, chunk in enumerate(reader.stream()):
            if i >= SCAN_CHUNKS:
                return None
            if chunk.entity_path != entity:
                continue
            batch = chunk.to_record_batch()
            if "inputs" not in batch.schema.names:
                return None
            for value in batch.column("inputs").to_pylist():
                text = value[0] if isinstance(value, list) and value else value
                if isinstance(text, str):
                    return BlueprintInputs.from_json(text)
            return None
    except Exception:  # a truncated or foreign file: no inputs, the viewer still gets the file
        return None
    return None
