"""Validation of the states and times handed to a sensor: clear errors naming the sensor."""
from __future__ import annotations

import numpy as np

from cistrack.errors import MeasurementError

__all__ = ["checked_states", "checked_times"]


def checked_states(label: str, states) -> np.ndarray:
    """``states`` as a finite (N, 6) float array, else MeasurementError naming sensor ``label``."""
    x = np.asarray(states, dtype=float)
    if x.ndim != 2 or x.shape[1] != 6:
        raise MeasurementError(f"sensor {label!r}: states must have shape (N, 6), got {x.shape}")
    if not np.all(np.isfinite(x)):
        raise MeasurementError(f"sensor {label!r}: states contain NaN or infinity")
    return x


def checked_times(label: str, t, n: int) -> np.ndarray:
    """``t`` as a finite scalar or (n,) float array, else MeasurementError naming ``label``."""
    tt = np.asarray(t, dtype=float)
    if not np.all(np.isfinite(tt)):
        raise MeasurementError(f"sensor {label!r}: times contain NaN or infinity")
    if tt.ndim == 0:
        return tt
    tt = tt.reshape(-1)
    if tt.shape[0] != n:
        raise MeasurementError(f"sensor {label!r}: t must be a scalar or have one time per row ({n}), "
                               f"got shape {np.shape(t)}")
    return tt
