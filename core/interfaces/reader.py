"""Reader: an observation file format, read into a MeasurementSet and written back out."""
from __future__ import annotations

from abc import abstractmethod
from datetime import datetime
from os import PathLike
from typing import ClassVar

from cistrack.interfaces.component import Component
from cistrack.model.measurement import MeasurementSet

__all__ = ["Reader"]


class Reader(Component):
    """An observation file format (registry kind ``"reader"``).

    ``read`` turns a file into a :class:`~cistrack.model.measurement.MeasurementSet` with times in TU
    since ``epoch`` (the scenario's UTC epoch), angles in rad, ranges in LU, and per-measurement
    site keys and types where the format has them; ``write`` writes a set so that ``read`` gives
    it back (to the format's stated resolution). A malformed file raises
    :class:`~cistrack.errors.MeasurementError` naming the file, the line and the field, and never
    quotes more of the file than the offending field.
    """

    kind = "reader"
    suffixes: ClassVar[tuple[str, ...]] = ()
    """File-name endings this format is recognised by (lower case, e.g. (".psv",))."""
    measurement_kinds: ClassVar[tuple[str, ...]] = ("azel",)
    """Measurement types the format carries ("azel", "radec")."""
    time_resolution_s: ClassVar[float] = 1e-6
    """Resolution of the times the writer writes, seconds (a round trip is exact to it)."""
    angle_resolution_rad: ClassVar[float] = 0.0
    """Resolution of the angles written, rad; 0: angles and sigmas round-trip bit for bit."""
    carries_sigmas: ClassVar[bool] = True
    """Whether per-measurement sigmas are written (otherwise the reader's defaults come back)."""

    @abstractmethod
    def read(self, path: str | PathLike, epoch: str | datetime) -> MeasurementSet:
        """Measurements of the file at ``path``; t = 0 at ``epoch`` (UTC)."""

    @abstractmethod
    def write(self, path: str | PathLike, measurements: MeasurementSet, epoch: str | datetime) -> None:
        """Write ``measurements`` (times TU since ``epoch``) to ``path``."""
