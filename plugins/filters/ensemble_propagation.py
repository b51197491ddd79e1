"""Propagating an ensemble and dropping the particles that hit a body."""
from __future__ import annotations

import numpy as np

from cistrack.errors import FilterError
from cistrack.interfaces import Dynamics

__all__ = ["propagate_ensemble"]


def propagate_ensemble(dynamics: Dynamics, states: np.ndarray, t0: float, t1: float,
                       who: str) -> tuple[np.ndarray, np.ndarray]:
    """One ``dynamics.propagate`` call for all ``states`` (N, 6) from t0 to t1 (TU).

    Returns (final states (N, 6), alive (N,) bool). Raises FilterError if the dynamics return
    non-finite states for particles that are alive.
    """
    prop = dynamics.propagate(states, float(t0), float(t1))
    final = np.array(prop.final, dtype=float)
    alive = np.asarray(prop.alive, dtype=bool)
    if not np.all(np.isfinite(final[alive])):
        raise FilterError(f"filter '{who}': dynamics returned NaN or infinite states for live particles")
    return final, alive
