"""A simple angles (and optional range) sensor used as a fixture by the conformance suite.

The observer stands on the Earth's surface at latitude ``latitude_deg`` and turns with the
Earth (the Earth–Moon plane is taken as the equator; the observer's longitude in the synodic
frame advances at the Earth's sidereal rate minus the synodic rate, starting on the +x axis).
It measures the direction of a target as an azimuth (in the synodic x–y plane, from +x towards
+y, [0, 2π)) and an elevation (from that plane, [-π/2, π/2]); there is no horizon, so targets
are always visible. Its components are named "azimuth" and "elevation"
(and "range", when ``range_fraction`` > 0) like the built-in ground telescope's, so a filter or
IOD method that picks components by name works with it. It is not registered as a plugin.
"""
from __future__ import annotations

import numpy as np

from cistrack.interfaces.component import check_nonnegative, check_positive, check_range
from cistrack.errors import ParameterError
from cistrack.interfaces.schedule import Pass
from cistrack.interfaces.sensor import Sensor
from cistrack.model.measurement import MeasurementSet
from cistrack.units import ARCSEC_RAD, LU_KM, TU_S
from cistrack.astro.primaries import EARTH_RADIUS_KM, MU_EARTH_MOON
from cistrack.testing.reference_dynamics import as_states

EARTH_ROTATION_RATE_RAD_S = 7.2921159e-5
"""Earth's sidereal rotation rate, rad/s."""

__all__ = ["GeocentricAnglesSensor"]


class GeocentricAnglesSensor(Sensor):
    """Angles in synodic axes from a point on the turning Earth, 1-sigma ``sigma_arcsec`` each.

    Parameters
    ----------
    sigma_arcsec : float
        One-sigma noise of azimuth and elevation, arcsec.
    range_fraction : float
        When > 0, a "range" component (LU) with one-sigma ``range_fraction`` x true range is
        added (the IOD-only range of the paper); 0 gives an angles-only sensor.
    latitude_deg : float
        Observer latitude, degrees.
    mu : float
        Mass ratio fixing the Earth's position (-mu, 0, 0).
    """

    def __init__(self, sigma_arcsec: float = 1.5, range_fraction: float = 0.0,
                 latitude_deg: float = 30.6, mu: float = MU_EARTH_MOON):
        self.sigma_arcsec = check_positive(self, "sigma_arcsec", sigma_arcsec)
        self.range_fraction = check_nonnegative(self, "range_fraction", range_fraction)
        self.latitude_deg = check_range(self, "latitude_deg", latitude_deg, -90.0, 90.0)
        self.mu = check_positive(self, "mu", mu)
        with_range = self.range_fraction > 0
        self.names = ("azimuth", "elevation", "range") if with_range else ("azimuth", "elevation")
        self.angular = (True, False, False) if with_range else (True, False)

    def observer_position(self, t) -> np.ndarray:
        """(3,) for scalar t, (K, 3) for t of shape (K,), LU."""
        t = np.asarray(t, dtype=float)
        lat = np.radians(self.latitude_deg)
        theta = (EARTH_ROTATION_RATE_RAD_S * TU_S - 1.0) * t
        r = EARTH_RADIUS_KM / LU_KM
        p = np.stack([-self.mu + r * np.cos(lat) * np.cos(theta), r * np.cos(lat) * np.sin(theta),
                      np.full_like(theta, r * np.sin(lat))], axis=-1)
        return p

    def _observer_rows(self, n: int, t) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        if t.ndim not in (0, 1) or (t.ndim == 1 and t.shape[0] != n):
            raise ParameterError(f"{self._label()}: t must be a scalar or have one time per state ({n}), got shape {t.shape}")
        return np.broadcast_to(self.observer_position(t), (n, 3))

    def measure(self, states: np.ndarray, t) -> np.ndarray:
        """(N, m): azimuth, elevation [rad] and optionally range [LU]."""
        x = as_states(self, states)
        rel = x[:, :3] - self._observer_rows(x.shape[0], t)
        rho = np.linalg.norm(rel, axis=1)
        az = np.mod(np.arctan2(rel[:, 1], rel[:, 0]), 2.0 * np.pi)
        el = np.arcsin(np.clip(rel[:, 2] / rho, -1.0, 1.0))
        cols = [az, el, rho] if self.range_fraction > 0 else [az, el]
        return np.stack(cols, axis=1)

    def sigmas(self, states: np.ndarray, t) -> np.ndarray:
        """(N, m) one-sigma noise: rad, rad (and LU)."""
        x = as_states(self, states)
        ang = np.full(x.shape[0], self.sigma_arcsec * ARCSEC_RAD)
        if self.range_fraction > 0:
            rho = np.linalg.norm(x[:, :3] - self._observer_rows(x.shape[0], t), axis=1)
            return np.stack([ang, ang, self.range_fraction * rho], axis=1)
        return np.stack([ang, ang], axis=1)

    def visible(self, states: np.ndarray, t) -> np.ndarray:
        """Always visible (the fixture has no horizon): (N,) True."""
        return np.ones(as_states(self, states).shape[0], dtype=bool)

    def line_of_sight(self, angles: np.ndarray, t) -> np.ndarray:
        """Unit vectors (N, 3) for azimuth/elevation pairs (N, 2) rad."""
        a = np.atleast_2d(np.asarray(angles, dtype=float))
        if a.shape[1] != 2:
            raise ParameterError(f"{self._label()}: angles must have shape (N, 2), got {a.shape}")
        az, el = a[:, 0], a[:, 1]
        return np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)], axis=1)

    def passes(self, times: np.ndarray, states: np.ndarray) -> list[Pass]:
        times = np.asarray(times, dtype=float)
        return [Pass(float(times[0]), float(times[-1]))] if times.size else []

    def simulate(self, states: np.ndarray, times: np.ndarray, rng: np.random.Generator) -> MeasurementSet:
        """Noisy measurements of ``states`` (K, 6) at ``times`` (K,) TU."""
        x = as_states(self, states)
        times = np.asarray(times, dtype=float).reshape(-1)
        if times.shape[0] != x.shape[0]:
            raise ParameterError(f"{self._label()}: {x.shape[0]} states but {times.shape[0]} times")
        z = self.measure(x, times)
        s = self.sigmas(x, times)
        noisy = z + s * rng.standard_normal(z.shape)
        noisy[:, 0] = np.mod(noisy[:, 0], 2.0 * np.pi)
        return MeasurementSet(times, noisy, s, self.names)
