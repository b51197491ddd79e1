"""Where a point lies on the Moon or the Earth: selenographic latitude and longitude in the Moon's
mean-Earth/polar-axis (ME) frame, geodetic latitude and longitude on WGS84.

- **Moon**: the orientation of the lunar principal-axis (PA) frame comes from DE421's physical
  librations (the Euler angles phi, theta, psi of the ``librations`` series read by ``jplephem``;
  ICRF -> PA = R3(psi) R1(theta) R3(phi), passive rotations), and PA -> ME is DE421's constant
  rotation R1(-0.30") R2(-78.56") R3(-67.92") (Williams, Boggs & Folkner 2008, "DE421 lunar
  orbit, physical librations, and surface coordinates"; the same angles as NAIF's
  ``moon_080317.tf`` frame MOON_ME_DE421). The ME frame is the one lunar maps and the IAU use
  (x towards the mean Earth direction, z along the mean rotation axis). Over 2026 it agrees with
  the IAU WGCCRE rotation model of the Moon (Archinal et al. 2011, itself an approximation of ME)
  to 12" (105 m on the surface), while the PA frame differs from both by about 100" (0.9 km) and
  the PA -> ME rotation with the opposite sign by 210" (tests/fit/test_orbit_events.py).
- **Earth**: GCRS -> ITRS by ERFA's IAU 2006/2000A ``c2t06a`` with the bundled IERS UT1-UTC and
  polar motion (:mod:`cistrack.astro.timescales`), then WGS84 geodetic coordinates (``gc2gd``).

Positions are body-centred, km, in GCRS (ICRF-aligned) axes; times are TDB Julian dates (Moon) or
UTC (Earth); angles out are degrees, East longitude in (-180, 180].
"""
from __future__ import annotations

from datetime import datetime
from functools import lru_cache

import erfa
import numpy as np

__all__ = ["moon_me_rotation", "selenographic", "geodetic", "PA_TO_ME_ARCSEC"]

PA_TO_ME_ARCSEC = (67.92, 78.56, 0.30)
"""DE421's rotation from the lunar principal-axis to the mean-Earth frame: angles about z, y, x,
arcseconds (applied as R1(-0.30") R2(-78.56") R3(-67.92"), passive)."""
_ARCSEC = np.pi / (180.0 * 3600.0)


def _r1(a: np.ndarray) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    o, z = np.ones_like(a), np.zeros_like(a)
    return np.stack([np.stack([o, z, z], -1), np.stack([z, c, s], -1), np.stack([z, -s, c], -1)], -2)


def _r2(a: np.ndarray) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    o, z = np.ones_like(a), np.zeros_like(a)
    return np.stack([np.stack([c, z, -s], -1), np.stack([z, o, z], -1), np.stack([s, z, c], -1)], -2)


def _r3(a: np.ndarray) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    o, z = np.ones_like(a), np.zeros_like(a)
    return np.stack([np.stack([c, s, z], -1), np.stack([-s, c, z], -1), np.stack([z, z, o], -1)], -2)


@lru_cache(maxsize=1)
def _librations():
    import de421
    from jplephem.ephem import Ephemeris

    return Ephemeris(de421)


def moon_me_rotation(jd1, jd2=0.0) -> np.ndarray:
    """Rotation matrices (K, 3, 3), ``v_ME = M @ v_ICRF``, at TDB Julian dates ``jd1 + jd2`` (K,)."""
    a = np.atleast_1d(np.asarray(jd1, dtype=float)).reshape(-1)
    b = np.broadcast_to(np.asarray(jd2, dtype=float), a.shape).astype(float)
    phi, theta, psi = np.asarray(_librations().position("librations", a, b), dtype=float).reshape(3, -1)
    pa = _r3(psi) @ _r1(theta) @ _r3(phi)
    z, y, x = (np.full(a.shape, -v * _ARCSEC) for v in PA_TO_ME_ARCSEC)
    return _r1(x) @ _r2(y) @ _r3(z) @ pa


def _lat_lon(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    lat = np.degrees(np.arctan2(v[:, 2], np.hypot(v[:, 0], v[:, 1])))
    return lat, np.degrees(np.arctan2(v[:, 1], v[:, 0]))


def selenographic(r_km, jd1, jd2=0.0) -> tuple[np.ndarray, np.ndarray]:
    """Selenocentric (ME) latitude and East longitude, degrees (K,), of Moon-centred GCRS positions
    ``r_km`` (K, 3) at TDB Julian dates ``jd1 + jd2`` (K,)."""
    r = np.atleast_2d(np.asarray(r_km, dtype=float))
    return _lat_lon(np.einsum("kij,kj->ki", moon_me_rotation(jd1, jd2), r))


def geodetic(r_km, utc: datetime, seconds) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """WGS84 geodetic latitude, East longitude (degrees) and height (km), each (K,), of geocentric
    GCRS positions ``r_km`` (K, 3) at ``seconds`` (K,) SI seconds after the UTC instant ``utc``."""
    from cistrack.astro.timescales import time_scales

    r = np.atleast_2d(np.asarray(r_km, dtype=float))
    sc = time_scales(utc, np.atleast_1d(np.asarray(seconds, dtype=float)).reshape(-1))
    m = erfa.c2t06a(*sc.tt, *sc.ut1, sc.orientation.xp, sc.orientation.yp)
    itrs = np.einsum("kij,kj->ki", np.broadcast_to(m, (r.shape[0], 3, 3)), r)
    lon, lat, h = erfa.gc2gd(1, itrs * 1000.0)
    return np.degrees(lat), np.degrees(lon), h / 1000.0
