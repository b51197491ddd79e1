"""Filter: initialise from a cloud, predict, update; exposes its belief."""
from __future__ import annotations

from abc import abstractmethod

import numpy as np

from ..belief import Belief, ParticleCloud
from ..component import Component
from ..measurement import Measurement
from .dynamics import Dynamics
from .sensor import Sensor

__all__ = ["Filter"]


class Filter(Component):
    """A recursive estimator.

    Lifecycle: ``initialize(cloud, dynamics, sensor, rng)`` once, then for each measurement
    ``predict(t)`` followed by ``update(measurement)``. ``belief`` is valid after each call.
    """

    kind = "filter"

    @abstractmethod
    def initialize(self, cloud: ParticleCloud, dynamics: Dynamics, sensor: Sensor,
                   rng: np.random.Generator) -> None:
        """Start from the IOD cloud (N, 6) at ``cloud.epoch``."""

    @abstractmethod
    def predict(self, t: float) -> None:
        """Propagate the belief to time ``t`` (TU)."""

    @abstractmethod
    def update(self, measurement: Measurement) -> None:
        """Condition the belief on one measurement taken at the current time."""

    @property
    @abstractmethod
    def belief(self) -> Belief:
        """The current density as a Gaussian mixture plus samples."""

    @property
    def diagnostics(self) -> dict[str, float]:
        """Per-step numbers worth recording (components, particles lost to impacts, ...)."""
        return {}
