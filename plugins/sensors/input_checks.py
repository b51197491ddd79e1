"""Validation of the states and times handed to a sensor: clear errors naming the sensor."""
from __future__ import annotations

import numpy as np

from cistrack.errors import MeasurementError

__all__ = ["checked_states", "checked_times", "checked_pass_samples"]


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


def checked_pass_samples(label: str, times, states) -> tuple[np.ndarray, np.ndarray]:
    """``(times (K,), states (K, 6))`` for a sensor's ``passes``: finite states, one per time, times
    strictly increasing; else MeasurementError naming sensor ``label``."""
    tt = np.asarray(times, dtype=float).reshape(-1)
    x = checked_states(label, states)
    if x.shape[0] != tt.shape[0]:
        raise MeasurementError(f"sensor {label!r}: passes needs times (K,) and states (K, 6), got "
                               f"{tt.shape} and {x.shape}")
    if tt.size > 1 and np.any(np.diff(tt) <= 0):
        raise MeasurementError(f"sensor {label!r}: pass times must increase strictly")
    return tt, x
