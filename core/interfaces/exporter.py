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
    ``meta`` carries ``object_name``, ``object_id`` and ``originator``, and may carry ``comments``
    (a list of one-line texts the file should carry as comments, e.g. that the run did not finish).
    ``path`` is a temporary file that ``cistrack export`` renames onto the target once written.
    """

    kind = "exporter"
    suffix: ClassVar[str] = ""
    """The file-name ending written by default (e.g. ".oem")."""

    @abstractmethod
    def write(self, path: str | PathLike, estimates, meta: dict) -> None:
        """Write ``estimates`` to ``path``."""
