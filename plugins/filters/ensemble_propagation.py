"""Propagating an ensemble and dropping the particles that hit a body."""
from __future__ import annotations

import numpy as np

from cistrack.errors import FilterError
from cistrack.interfaces import Dynamics

from .process_noise import velocity_random_walk_covariance

__all__ = ["propagate_ensemble", "propagate_particles"]


def propagate_ensemble(dynamics: Dynamics, states: np.ndarray, t0: float, t1: float,
                       who: str) -> tuple[np.ndarray, np.ndarray]:
    """One ``dynamics.propagate`` call for all ``states`` (N, 6) from t0 to t1 (TU).

    Returns (final states (N, 6), alive (N,) bool); the states are the propagation's own array
    (a view of its last output time), not a copy. Raises FilterError if the dynamics return
    non-finite states for particles that are alive.
    """
    prop = dynamics.propagate(states, float(t0), float(t1))
    final = np.asarray(prop.final, dtype=float)  # no copy: at 1e6 particles each copy is 48 MB
    alive = np.asarray(prop.alive, dtype=bool)
    if not np.all(np.isfinite(final).all(axis=1)[alive]):
        raise FilterError(f"filter '{who}': dynamics returned NaN or infinite states for live particles")
    return final, alive


def propagate_particles(dynamics: Dynamics, states: np.ndarray, t0: float, t1: float, who: str,
                        velocity_noise_kms_per_sqrt_day: float,
                        rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Propagate particles (N, 6) from t0 to t1 (TU), drop those that hit a body, and add the
    optional velocity random-walk process noise.

    Returns (surviving states (M, 6), alive (N,) bool). Raises FilterError when no particle
    survives. Used by the particle filters (PGM, SIR); sigma-point filters keep every point and
    call :func:`propagate_ensemble` directly.
    """
    x, alive = propagate_ensemble(dynamics, states, t0, t1, who)
    if not np.any(alive):
        raise FilterError(f"filter '{who}': every particle hit a body before t = {t1} TU")
    x = x[alive]
    q = velocity_random_walk_covariance(velocity_noise_kms_per_sqrt_day, t1 - t0, x.shape[1])
    if np.any(q):
        x = x + rng.standard_normal(x.shape) * np.sqrt(np.diag(q))
    return x, alive
