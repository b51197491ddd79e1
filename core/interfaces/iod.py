"""IOD method: measurements of the first pass -> a particle cloud."""
from __future__ import annotations

from abc import abstractmethod

import numpy as np

from cistrack.model.belief import ParticleCloud
from cistrack.interfaces.component import Component
from cistrack.model.measurement import MeasurementSet
from cistrack.interfaces.sensor import Sensor

__all__ = ["IODMethod"]


class IODMethod(Component):
    """Initial orbit determination from the measurements of the first pass."""

    kind = "iod"

    @abstractmethod
    def estimate(self, measurements: MeasurementSet, sensor: Sensor,
                 rng: np.random.Generator) -> ParticleCloud:
        """A particle cloud (N, 6), nondimensional synodic, at the epoch of the last measurement
        the method used. Filtering continues with the measurements after that epoch.

        ``measurements`` is the whole measurement set (possibly including an IOD-only 'range'
        component); the method chooses which of them to use and raises
        :class:`~cistrack.errors.IODError` with a clear message if they do not suffice.
        """
