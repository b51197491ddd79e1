"""What a particle filter with a velocity random walk declares to the framework: the process noise
it adds (``Filter.process_noise``, used by the information bound) and the memory its particles
need (``Component.memory_need``, checked before a run)."""
from __future__ import annotations

import numpy as np

from cistrack.interfaces.component import MemoryNeed

from .process_noise import velocity_random_walk_covariance

__all__ = ["ParticleFilterDeclarations"]


class ParticleFilterDeclarations:
    """Mixin for filters with ``n_particles`` and ``velocity_noise_kms_per_sqrt_day`` attributes
    (PGM, EnKF, bootstrap and regularised SIR); put it before the filter base class."""

    n_particles: int
    velocity_noise_kms_per_sqrt_day: float

    def process_noise(self, t0: float, t1: float) -> np.ndarray | None:
        """The velocity random walk added from ``t0`` to ``t1`` (TU), (6, 6); None when off."""
        if self.velocity_noise_kms_per_sqrt_day <= 0:
            return None
        return velocity_random_walk_covariance(self.velocity_noise_kms_per_sqrt_day, t1 - t0)

    def memory_need(self) -> MemoryNeed:
        """Its particles (``n_particles``)."""
        return MemoryNeed.particles(self.n_particles)
