"""IOD method: measurements of the first pass -> a particle cloud."""
from __future__ import annotations

from abc import abstractmethod

import numpy as np

from cistrack.model.belief import ParticleCloud
from cistrack.interfaces.component import Component, check_int
from cistrack.model.measurement import MeasurementSet
from cistrack.interfaces.sensor import Sensor

__all__ = ["IODMethod", "MIN_IOD_PARTICLES", "check_iod_particles"]

MIN_IOD_PARTICLES = 100
"""Fewest particles an IOD cloud may have. The cloud is the filter's first belief over a 6-D
state: its covariance needs at least 7 particles to have full rank, and a mixture fitted to it
(the PGM's components) several per component, so a handful of particles ends in a collapsed or
degenerate belief; 100 is a small cloud that still describes one."""


def check_iod_particles(owner: Component, value: object) -> int:
    """``value`` as an IOD's ``n_particles``: an integer >= :data:`MIN_IOD_PARTICLES` (the
    ParameterError says why)."""
    n = check_int(owner, "n_particles", value)
    if n < MIN_IOD_PARTICLES:
        owner._fail("n_particles", value, f"must be >= {MIN_IOD_PARTICLES}: the IOD's cloud is the filter's "
                                          "first belief over a 6-D state, and fewer particles cannot describe "
                                          "it (its covariance needs at least 7 to have full rank, a mixture "
                                          "several per component); a smaller cloud ends in a collapsed belief")
    return n


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
