"""Directions on the sky of a target seen from a moving observer: light time and RA/Dec.

Vectors are in an inertial frame with ICRF-like axes (see :mod:`.space_frames`); km, km/s, km/s^2.
"""
from __future__ import annotations

import numpy as np

from cistrack.astro.observer import C_KMS

__all__ = ["astrometric_direction", "radec_of", "unit_of_radec", "LIGHT_TIME_ITERATIONS"]

LIGHT_TIME_ITERATIONS = 4
"""Fixed-point iterations of the light time; each gains a factor |v| / c ~ 1e-5 in cislunar space."""

_TWO_PI = 2.0 * np.pi


def astrometric_direction(target: np.ndarray, observer: np.ndarray, accel: np.ndarray,
                          drift: np.ndarray) -> np.ndarray:
    """Observer -> target vector (N, 3) km with light time: ``p = r_t(t - tau) - r_o(t) - drift tau``,
    ``|p| = c tau``.

    target (N, 6) and observer (N or 1, 6) inertial states at the reception time t (km, km/s);
    accel (N, 3) the target's inertial acceleration (its path over tau to second order:
    ``r_t(t - tau) = r - v tau + a tau^2 / 2``); drift (N or 1, 3) the velocity of the frame's
    origin in the frame light travels straight in (the Earth's barycentric velocity for GCRS,
    zero for a barycentric frame).
    """
    geo = target[:, :3] - observer[:, :3]
    vel = target[:, 3:] + drift
    tau = np.linalg.norm(geo, axis=1) / C_KMS
    for _ in range(LIGHT_TIME_ITERATIONS):
        p = geo - vel * tau[:, None] + 0.5 * accel * (tau * tau)[:, None]
        tau = np.linalg.norm(p, axis=1) / C_KMS
    return geo - vel * tau[:, None] + 0.5 * accel * (tau * tau)[:, None]


def radec_of(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Right ascension [0, 2pi) and declination [-pi/2, pi/2] (rad) of vectors p (N, 3)."""
    ra = np.mod(np.arctan2(p[:, 1], p[:, 0]), _TWO_PI)
    ra = np.where(ra >= _TWO_PI, 0.0, ra)
    return ra, np.arctan2(p[:, 2], np.hypot(p[:, 0], p[:, 1]))


def unit_of_radec(ra, dec) -> np.ndarray:
    """Unit vectors (N, 3) of right ascensions and declinations (rad, (N,) each)."""
    ra, dec = np.asarray(ra, dtype=float), np.asarray(dec, dtype=float)
    cd = np.cos(dec)
    return np.stack([cd * np.cos(ra), cd * np.sin(ra), np.sin(dec)], axis=-1)
