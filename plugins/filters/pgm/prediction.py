"""The PGM's ``pgm-prediction`` step: propagation of every particle, with optional process noise."""
from __future__ import annotations

import numpy as np

from cistrack.interfaces import Dynamics
from cistrack.interfaces.component import check_nonnegative
from cistrack.interfaces.pgm_steps import ParticlePrediction

from ..ensemble_propagation import propagate_particles

__all__ = ["PropagateParticles"]


class PropagateParticles(ParticlePrediction):
    """Every particle propagated by the dynamics (one vectorised call); those that hit a body are
    dropped; an optional velocity random walk is added.

    Parameters
    ----------
    velocity_noise_kms_per_sqrt_day : float
        Velocity random walk, km/s after one day (0 = off).
    """

    def __init__(self, velocity_noise_kms_per_sqrt_day: float = 0.0):
        self.velocity_noise_kms_per_sqrt_day = check_nonnegative(
            self, "velocity_noise_kms_per_sqrt_day", velocity_noise_kms_per_sqrt_day)

    def predict(self, dynamics: Dynamics, states: np.ndarray, t0: float, t1: float, rng: np.random.Generator,
                steps: np.ndarray | None, who: str) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """Survivors (M, 6) at ``t1`` (TU), alive (N,) bool, their next steps (M,) TU or None."""
        return propagate_particles(dynamics, states, t0, t1, who, self.velocity_noise_kms_per_sqrt_day, rng, steps)
