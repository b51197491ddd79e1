"""Optional process noise: a velocity random walk, off by default."""
from __future__ import annotations

import numpy as np

from cistrack.interfaces.component import check_range
from cistrack.units import DAY_S, TU_S, VU_KMS

__all__ = ["velocity_random_walk_covariance", "check_velocity_noise", "MAX_VELOCITY_NOISE_KMS_PER_SQRT_DAY"]

MAX_VELOCITY_NOISE_KMS_PER_SQRT_DAY = 1.0
"""The largest velocity random walk a filter takes (km/s after one day): a cislunar orbit's whole
speed; more is a unit mistake (a day's noise larger than the orbit itself)."""


def check_velocity_noise(owner, value) -> float:
    """``velocity_noise_kms_per_sqrt_day`` as float; ParameterError unless in [0, 1] km/s/sqrt(day)."""
    return check_range(owner, "velocity_noise_kms_per_sqrt_day", value, 0.0, MAX_VELOCITY_NOISE_KMS_PER_SQRT_DAY)


def velocity_random_walk_covariance(sigma_kms_per_sqrt_day: float, dt_tu: float, dim: int = 6) -> np.ndarray:
    """Process noise Q (dim, dim) accumulated over ``dt_tu`` (TU) by a velocity random walk with
    one-sigma ``sigma_kms_per_sqrt_day`` (km/s after one day); position noise is zero.

    Q[3:, 3:] = (sigma/VU)^2 * |dt| in days * I.
    """
    q = np.zeros((dim, dim))
    if sigma_kms_per_sqrt_day > 0 and dt_tu != 0:
        days = abs(float(dt_tu)) * TU_S / DAY_S
        var = (sigma_kms_per_sqrt_day / VU_KMS) ** 2 * days
        idx = np.arange(3, dim)
        q[idx, idx] = var
    return q
