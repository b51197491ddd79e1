"""Exporter: writes a run's orbit estimate in a standard format (CCSDS OEM, OPM, ...)."""
from __future__ import annotations

from abc import abstractmethod
from os import PathLike
from typing import ClassVar

from cistrack.interfaces.component import Component

__all__ = ["Exporter"]


class Exporter(Component):
    """An estimate file format (registry kind ``"exporter"``).

    ``write(path, estimates, meta)`` writes :class:`cistrack.results.inertial_frame.InertialEstimates`
    (UTC times, Earth-centred inertial km, km/s states and covariances in a named frame);
    ``meta`` carries ``object_name``, ``object_id`` and ``originator``.
    """

    kind = "exporter"
    suffix: ClassVar[str] = ""
    """The file-name ending written by default (e.g. ".oem")."""

    @abstractmethod
    def write(self, path: str | PathLike, estimates, meta: dict) -> None:
        """Write ``estimates`` to ``path``."""
