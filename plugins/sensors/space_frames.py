"""Where things are for an observer in space: the inertial frame light travels straight in, and
the Sun, Earth and Moon in it.

Two models, picked from the run's dynamics (:func:`sky_for`):

:class:`IdealSky` (CR3BP)
    The paper's equatorial geometry (:class:`~cistrack.plugins.sensors.frames.EquatorialFrameModel`):
    the Earth-Moon plane is the equator, the synodic x axis has right ascension
    ``moon_phase_deg + t`` (t in TU). The inertial frame is centred on the barycentre, which is
    unaccelerated in the CR3BP, so light time is solved there; its axes are the equatorial
    model's ECI axes, so right ascension and declination are that model's. The Sun, which the
    CR3BP does not have, is placed by the Astronomical Almanac's low-precision solar
    coordinates (about 0.01 deg, 1e-4 AU from 1950 to 2050) at the UTC of t, taken as the
    direction in the model's ECI axes.
:class:`RealSky` (ephemeris)
    The real Earth-Moon frame of :class:`cistrack.astro.earth_moon.EarthMoonFrame` (DE421): the
    frame is GCRS (geocentric, ICRF axes); light time is solved in the barycentric frame (BCRS),
    which adds the Earth's barycentric motion over the light time (``drift``), as for the ground
    telescope's astrometric RA/Dec (:mod:`cistrack.astro.sky`). Sun and Moon from DE421.

All positions km, velocities km/s, accelerations km/s^2, times TU since the scenario epoch.
"""
from __future__ import annotations

from datetime import datetime

import numpy as np

from cistrack import units
from cistrack.astro.observer import AU_KM
from cistrack.astro.primaries import EARTH_RADIUS_KM, MOON_RADIUS_KM, MU_EARTH_MOON
from cistrack.astro.rotating_frame import rot_z

from .frames import days_since_j2000

__all__ = ["IdealSky", "RealSky", "sky_for", "almanac_sun_eci_km", "SUN_RADIUS_KM"]

SUN_RADIUS_KM: float = 695_700.0
"""Nominal solar radius (IAU 2015 Resolution B3), km."""

_ACC = units.LU_KM / units.TU_S ** 2   # km/s^2 per LU/TU^2


def almanac_sun_eci_km(epoch: datetime, t) -> np.ndarray:
    """Geocentric Sun (K, 3) km, mean equator and equinox of date, at t (scalar or (K,) TU) after
    ``epoch`` (UTC): the Astronomical Almanac's low-precision formula (section C, ~0.01 deg)."""
    whole, frac = days_since_j2000(epoch)
    n = whole + frac + np.atleast_1d(np.asarray(t, dtype=float)).reshape(-1) * units.TU_DAYS
    g = np.radians(357.528 + 0.9856003 * n)
    lam = np.radians(280.460 + 0.9856474 * n + 1.915 * np.sin(g) + 0.020 * np.sin(2.0 * g))
    eps = np.radians(23.439 - 4e-7 * n)
    r = (1.00014 - 0.01671 * np.cos(g) - 0.00014 * np.cos(2.0 * g)) * AU_KM
    return np.stack([r * np.cos(lam), r * np.cos(eps) * np.sin(lam), r * np.sin(eps) * np.sin(lam)], axis=1)


class IdealSky:
    """The CR3BP's barycentric inertial frame with the equatorial model's axes (module docstring).

    Parameters: ``epoch`` (UTC datetime of t = 0), ``moon_phase_deg`` (right ascension of the
    synodic x axis at t = 0, degrees), ``mu`` (the model's mass ratio).
    """

    name = "ideal-equatorial"
    radii_km = {"sun": SUN_RADIUS_KM, "earth": EARTH_RADIUS_KM, "moon": MOON_RADIUS_KM}

    def __init__(self, epoch: datetime, moon_phase_deg: float = 0.0, mu: float = MU_EARTH_MOON) -> None:
        self.epoch = epoch
        self.moon_phase_deg = float(moon_phase_deg)
        self.mu = float(mu)

    def rotation(self, t) -> np.ndarray:
        """Synodic -> inertial axes (K, 3, 3) at t (scalar or (K,) TU)."""
        tt = np.atleast_1d(np.asarray(t, dtype=float)).reshape(-1)
        return rot_z(np.radians(self.moon_phase_deg) + tt)

    def states_km(self, states: np.ndarray, t) -> np.ndarray:
        """Synodic states (N, 6) at t (scalar or (N,) TU) -> inertial (N, 6) km, km/s."""
        x = np.asarray(states, dtype=float)
        rot = np.broadcast_to(self.rotation(t), (x.shape[0], 3, 3))
        v = x[:, 3:].copy()
        v[:, 0] -= x[:, 1]                               # + omega x r, omega = (0, 0, 1) rad/TU
        v[:, 1] += x[:, 0]
        return np.concatenate([np.einsum("nij,nj->ni", rot, x[:, :3]) * units.LU_KM,
                               np.einsum("nij,nj->ni", rot, v) * units.VU_KMS], axis=1)

    def gravity_kms2(self, states: np.ndarray, t) -> np.ndarray:
        """Inertial acceleration (N, 3) km/s^2 of synodic states (N, 6) at t: Earth and Moon point
        masses (what bends the target's path during the light time)."""
        x = np.asarray(states, dtype=float)[:, :3]
        acc = np.zeros_like(x)
        for m, xb in ((1.0 - self.mu, -self.mu), (self.mu, 1.0 - self.mu)):
            d = x - np.array([xb, 0.0, 0.0])
            acc -= m * d / np.linalg.norm(d, axis=1)[:, None] ** 3
        rot = np.broadcast_to(self.rotation(t), (x.shape[0], 3, 3))
        return np.einsum("nij,nj->ni", rot, acc) * _ACC

    def drift_kms(self, t) -> np.ndarray:
        """Velocity (K, 3) km/s of the frame's origin in the light-time frame: 0 (barycentre)."""
        return np.zeros((np.atleast_1d(np.asarray(t, dtype=float)).size, 3))

    def bodies_km(self, t) -> dict[str, np.ndarray]:
        """Sun, Earth and Moon positions (K, 3) km at t (scalar or (K,) TU), inertial frame."""
        rot = self.rotation(t)
        earth = rot[:, :, 0] * (-self.mu * units.LU_KM)
        moon = rot[:, :, 0] * ((1.0 - self.mu) * units.LU_KM)
        sun = earth + almanac_sun_eci_km(self.epoch, t)
        return {"sun": sun, "earth": earth, "moon": moon}


class RealSky:
    """GCRS of the real Earth-Moon frame, with BCRS light time (module docstring).

    Parameters: ``frame`` (an :class:`~cistrack.astro.earth_moon.EarthMoonFrame`).
    """

    name = "gcrs"
    radii_km = {"sun": SUN_RADIUS_KM, "earth": EARTH_RADIUS_KM, "moon": MOON_RADIUS_KM}

    def __init__(self, frame) -> None:
        self.frame = frame

    def rotation(self, t) -> np.ndarray:
        """Synodic -> GCRS axes (K, 3, 3) at t (scalar or (K,) TU)."""
        return self.frame.axes(t).rotation

    def states_km(self, states: np.ndarray, t) -> np.ndarray:
        """Synodic states (N, 6) at t (scalar or (N,) TU) -> GCRS (N, 6) km, km/s."""
        x = np.asarray(states, dtype=float)
        tt = np.asarray(t, dtype=float)
        if tt.ndim == 0 or tt.size == 1:
            return np.atleast_2d(self.frame.synodic_to_gcrs(x, float(tt.reshape(-1)[0])))
        uniq, inv = np.unique(tt, return_inverse=True)
        if uniq.size == 1:
            return np.atleast_2d(self.frame.synodic_to_gcrs(x, float(uniq[0])))
        return self.frame.synodic_to_gcrs(x, tt)

    def gravity_kms2(self, states: np.ndarray, t) -> np.ndarray:
        """Zero (N, 3): over a light time of at most ~1.5 s the straight path misses by < 1 m,
        below 0.003 arcsec at lunar distance (the ephemeris tolerance is 0.01 arcsec)."""
        return np.zeros((np.asarray(states).shape[0], 3))

    def _jd(self, t):
        jd1, jd2 = self.frame.epoch_tdb
        return jd1, jd2 + self.frame.tdb_days(t)

    def drift_kms(self, t) -> np.ndarray:
        """Barycentric velocity (K, 3) km/s of the geocentre (DE421) at t (scalar or (K,) TU)."""
        eph = self.frame.ephemeris
        jd1, jd2 = self._jd(t)
        a = np.full(jd2.shape, jd1)
        _, v_emb = eph._raw("earthmoon", a, jd2)
        _, v_moon = eph._raw("moon", a, jd2)
        return v_emb - eph.earth_share * v_moon

    def bodies_km(self, t) -> dict[str, np.ndarray]:
        """Sun, Earth and Moon positions (K, 3) km at t (scalar or (K,) TU), GCRS (DE421)."""
        eph = self.frame.ephemeris
        jd1, jd2 = self._jd(t)
        sun = np.atleast_2d(eph.sun(jd1, jd2)[0])
        moon = np.atleast_2d(eph.moon(jd1, jd2)[0])
        return {"sun": sun, "earth": np.zeros_like(sun), "moon": moon}


def sky_for(dynamics, epoch: datetime, moon_phase_deg: float = 0.0):
    """The sky of a run under ``dynamics``: :class:`RealSky` for a model that carries a real
    Earth-Moon frame (``dynamics.frame``, the ephemeris model), else :class:`IdealSky` with the
    model's mass ratio (``dynamics.mu``, default the Earth-Moon value)."""
    frame = getattr(dynamics, "frame", None)
    if frame is not None and hasattr(frame, "synodic_to_gcrs"):
        return RealSky(frame)
    return IdealSky(epoch, moon_phase_deg, float(getattr(dynamics, "mu", MU_EARTH_MOON)))
