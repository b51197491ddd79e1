"""Where a ground observer is, in the GCRS, at UTC times: WGS84 site -> ITRS -> CIRS -> GCRS.

The chain is the IAU 2006/2000A CIO-based one, evaluated by ERFA (pyerfa):

- site: WGS84 geodetic latitude, longitude (East), height -> ITRS position (``erfa.gd2gc``);
- polar motion (x_p, y_p) and the TIO locator s' (``erfa.pom00``, ``erfa.sp00``), optional;
- Earth rotation angle of UT1 (``erfa.era00``); UT1-UTC optional (off: UT1 = UTC);
- celestial-to-intermediate matrix of precession-nutation and frame bias (``erfa.c2i06a``, TT).

The observer's velocity is the Earth's rotation alone (``erfa.pvtob``); precession-nutation
rates (< 1e-11 rad/s) are ignored. For stellar aberration the Earth's barycentric velocity
comes from ERFA's analytic ephemeris ``erfa.epv00`` (about 1e-9 AU/day, far below what
aberration needs; astropy's "builtin" ephemeris is the same model).

Earth orientation (UT1-UTC, polar motion) comes from :mod:`cistrack.astro.timescales` (bundled IERS
tables, documented fallback outside them). Lengths km, velocities km/s, angles rad.
"""
from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime

import numpy as np

from cistrack.astro.kept_by_time import kept_or_evaluated
from cistrack.astro.sites import Site
from cistrack.lazy import LazyModule
from cistrack.units import parse_utc

erfa = LazyModule("erfa")  # on first use: the command line and a CR3BP run do not need ERFA

__all__ = ["Site", "ObserverGeometry", "ObserverState", "site_itrs_km", "neu_basis", "AU_KM", "C_KMS"]

AU_KM: float = 149_597_870.700
"""Astronomical unit, km (IAU 2012)."""
C_KMS: float = 299_792.458
"""Speed of light, km/s."""
_DAY_S = 86_400.0


def site_itrs_km(site: Site) -> np.ndarray:
    """ITRS (Earth-fixed) position of a WGS84 site, km: (3,) (``erfa.gd2gc``)."""
    xyz = erfa.gd2gc(1, np.radians(site.longitude_deg), np.radians(site.latitude_deg),
                     float(site.height_m))
    return np.asarray(xyz, dtype=float) / 1000.0


def neu_basis(site: Site) -> np.ndarray:
    """Rows North, East, Up (geodetic) of a site in the ITRS: (3, 3); ``neu = B @ v_itrs``."""
    lat, lon = np.radians(site.latitude_deg), np.radians(site.longitude_deg)
    sl, cl, so, co = np.sin(lat), np.cos(lat), np.sin(lon), np.cos(lon)
    return np.array([[-sl * co, -sl * so, cl], [-so, co, 0.0], [cl * co, cl * so, sl]])


@dataclass(frozen=True)
class ObserverState:
    """The observer and the Earth at K times (arrays lead with K).

    Attributes
    ----------
    position_km, velocity_kms : (K, 3)
        Observer position and velocity relative to the geocentre, GCRS axes.
    gcrs_to_itrs : (K, 3, 3)
        Rotation ``v_itrs = M @ v_gcrs`` (bias-precession-nutation, Earth rotation, polar motion).
    earth_velocity_kms : (K, 3)
        Barycentric velocity of the geocentre, BCRS (= GCRS) axes.
    sun_distance_au : (K,)
        Sun-to-Earth distance, AU (for the relativistic aberration formula).
    """

    position_km: np.ndarray
    velocity_kms: np.ndarray
    gcrs_to_itrs: np.ndarray
    earth_velocity_kms: np.ndarray
    sun_distance_au: np.ndarray


class ObserverGeometry:
    """Observer states for one site and one UTC epoch, at seconds after the epoch.

    ``state(seconds)`` evaluates ERFA once per distinct time and keeps the most recent scalar
    times and vectors of times (filters ask for the same measurement time many times, a
    least-squares fit for the same vector).

    Parameters
    ----------
    site : cistrack.astro.sites.Site (WGS84 latitude, East longitude, height)
    epoch : datetime or ISO-8601 str, UTC instant of seconds = 0
    polar_motion : bool
        Apply polar motion (IERS x_p, y_p); off: the CIP is the ITRS z axis.
    ut1 : bool
        Use UT1 = UTC + (UT1-UTC) for the Earth rotation angle; off: UT1 = UTC.
    """

    _CACHE_SIZE = 64
    _KEPT_VECTORS = 4
    """Vectors of times whose states are kept (a least-squares fit asks for all its observation
    times at every iteration and for every column of its Jacobian: 19 times per fit of a
    319-observation arc)."""
    _KEPT_VECTOR_ROWS = 65_536
    """Longest vector of distinct times whose states are kept (152 bytes a time)."""

    def __init__(self, site: Site, epoch: datetime | str, *, polar_motion: bool = True,
                 ut1: bool = True) -> None:
        self.site = site
        self.epoch = parse_utc(epoch)
        self.polar_motion = bool(polar_motion)
        self.ut1 = bool(ut1)
        self._cache: dict[float, ObserverState] = {}
        self._kept: dict[tuple, ObserverState] = {}

    def state(self, seconds) -> ObserverState:
        """Observer state at ``seconds`` (scalar or (K,)) SI seconds after the epoch (K=1 for a scalar)."""
        s = np.atleast_1d(np.asarray(seconds, dtype=float)).reshape(-1)
        if s.size == 1:
            return kept_or_evaluated(self._cache, float(s[0]), self._CACHE_SIZE, lambda: self._evaluate(s))
        uniq, inv = np.unique(s, return_inverse=True)
        if uniq.size <= self._KEPT_VECTOR_ROWS:  # the states are handed out indexed: new arrays
            st = kept_or_evaluated(self._kept, (uniq.size, uniq.tobytes()), self._KEPT_VECTORS,
                                   lambda: self._evaluate(uniq))
        else:
            st = self._evaluate(uniq)
        return ObserverState(*(a[inv] for a in (st.position_km, st.velocity_kms, st.gcrs_to_itrs,
                                                 st.earth_velocity_kms, st.sun_distance_au)))

    def _evaluate(self, s: np.ndarray) -> ObserverState:
        from cistrack.astro import timescales as ts       # astropy loads on first use, not on import

        scales = ts.time_scales(self.epoch, s)
        eo = scales.orientation
        tt1, tt2 = scales.tt
        u1, u2 = scales.ut1 if self.ut1 else scales.utc
        xp = eo.xp if self.polar_motion else np.zeros_like(s)
        yp = eo.yp if self.polar_motion else np.zeros_like(s)
        sp = erfa.sp00(tt1, tt2)
        era = erfa.era00(u1, u2)
        rc2i = erfa.c2i06a(tt1, tt2)                                    # (K, 3, 3) GCRS -> CIRS
        rpom = erfa.pom00(xp, yp, sp)                                   # (K, 3, 3) TIRS -> ITRS
        c2t = erfa.c2tcio(rc2i, era, rpom)                              # (K, 3, 3) GCRS -> ITRS
        lat, lon = np.radians(self.site.latitude_deg), np.radians(self.site.longitude_deg)
        pv = erfa.pvtob(lon, lat, float(self.site.height_m), xp, yp, sp, era)   # (K, 2, 3) CIRS, m
        pos = np.einsum("kji,kj->ki", rc2i, pv["p"]) / 1000.0
        vel = np.einsum("kji,kj->ki", rc2i, pv["v"]) / 1000.0
        b1, b2 = scales.tdb
        pvh, pvb = erfa.epv00(b1, b2)                                   # AU, AU/day
        v_earth = np.asarray(pvb["v"], dtype=float) * (AU_KM / _DAY_S)
        d_sun = np.linalg.norm(np.asarray(pvh["p"], dtype=float), axis=1)
        return ObserverState(pos, vel, np.asarray(c2t, dtype=float), v_earth, d_sun)
