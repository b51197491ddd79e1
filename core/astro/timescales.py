"""Time scales: UTC, TAI, TT, TDB and UT1, leap seconds and Earth orientation, offline.

Every conversion goes through ``astropy.time`` (which calls ERFA, the IAU SOFA library); the
Earth orientation parameters (UT1-UTC and polar motion) come from the IERS tables bundled with
astropy (package ``astropy-iers-data``: IERS finals2000A, measured values from 1973 plus about
a year of IERS predictions). Nothing here downloads: importing this module sets
``astropy.utils.iers.conf.auto_download = False`` and ``auto_max_age = None`` for the process
(astropy then reads only the bundled tables, whatever their age; see docs/real-sky.md). The
parsed table is kept on disk by :mod:`cistrack.astro.iers_cache` (same values, read in
milliseconds instead of parsed in about a second).

Times are given as a UTC instant ``epoch`` (``datetime`` or ISO-8601 string) plus ``seconds``
(scalar or (K,) array) of elapsed SI seconds after it, i.e. physical (TAI) seconds, which is what
``t * TU_S`` of a propagation is. Across a leap second this differs by 1 s from adding the
seconds to the UTC clock reading.

Offline fallback outside the bundled tables (documented in docs/real-sky.md), the same choice
astropy makes for its own coordinate transforms:

- UT1-UTC = 0 s (|UT1-UTC| < 0.9 s by the definition of UTC: at most 13.5 arcsec of Earth
  rotation), polar motion = the 50-year mean pole (x, y) = (0.035, 0.29) arcsec;
- leap seconds: none after the last one in the bundled table (TAI-UTC = 37 s since 2017).

:func:`earth_orientation` says for each time whether the tables covered it.
"""
from __future__ import annotations

import warnings
from contextlib import contextmanager
from dataclasses import dataclass
from datetime import datetime

import erfa
import numpy as np
from astropy import units as u
from astropy.time import Time, TimeDelta
from astropy.utils import iers

from cistrack.astro.kept_by_time import kept_or_evaluated
from cistrack.units import DAY_S, parse_utc

__all__ = [
    "J2000_JD", "MEAN_POLE_ARCSEC", "EarthOrientation",
    "utc_time", "tai_jd", "tt_jd", "tdb_jd", "ut1_jd", "tdb_seconds_since_j2000",
    "tai_minus_utc", "earth_orientation", "TimeScales", "time_scales",
]

iers.conf.auto_download = False          # bundled IERS/leap-second tables only, never the network
iers.conf.auto_max_age = None            # and use them however old they are (no "stale table" error)

J2000_JD: float = 2451545.0
"""Julian date of J2000.0 (2000-01-01T12:00:00 TT; used here on the TDB scale)."""
MEAN_POLE_ARCSEC: tuple[float, float] = (0.035, 0.29)
"""Polar motion (x, y) used outside the IERS tables, arcsec (astropy's 50-year mean pole)."""
_ARCSEC_RAD = np.pi / (180.0 * 3600.0)


@contextmanager
def _quiet():
    """Silence ERFA's 'dubious year' warning for UTC after the leap-second table.

    ERFA warns for UTC dates more than a few years past its table; cistrack's documented rule is
    "no leap seconds after the last one tabulated", which is what ERFA computes anyway.
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", erfa.ErfaWarning)
        yield


def utc_time(epoch: datetime | str, seconds=0.0) -> Time:
    """astropy ``Time`` (scale UTC) at ``seconds`` SI seconds after the UTC instant ``epoch``.

    epoch : datetime (naive = UTC) or ISO-8601 string; seconds : scalar or (K,) s.
    Returns a scalar or (K,) Time.
    """
    try:
        dt = parse_utc(epoch)
    except (ValueError, TypeError) as exc:
        raise ValueError(f"epoch must be an ISO-8601 UTC time such as '2026-01-01T00:00:00Z', "
                         f"got {epoch!r}") from exc
    s = np.asarray(seconds, dtype=float)
    if not np.all(np.isfinite(s)):
        raise ValueError("seconds after the epoch contain NaN or infinity")
    with _quiet():
        t0 = Time(dt.replace(tzinfo=None), scale="utc", precision=9)
        if s.ndim == 0 and s == 0.0:
            return t0
        # Adding a TimeDelta works in TAI: the seconds are elapsed SI seconds.
        return t0 + TimeDelta(s, format="sec")


def _two_part(t: Time, scale: str) -> tuple[np.ndarray, np.ndarray]:
    with _quiet():
        other = getattr(t, scale)
        return np.asarray(other.jd1, dtype=float), np.asarray(other.jd2, dtype=float)


def tai_jd(epoch: datetime | str, seconds=0.0) -> tuple[np.ndarray, np.ndarray]:
    """Two-part Julian date (jd1, jd2) on TAI; shapes follow ``seconds`` (scalar or (K,))."""
    return _two_part(utc_time(epoch, seconds), "tai")


def tt_jd(epoch: datetime | str, seconds=0.0) -> tuple[np.ndarray, np.ndarray]:
    """Two-part Julian date (jd1, jd2) on TT (= TAI + 32.184 s)."""
    return _two_part(utc_time(epoch, seconds), "tt")


def tdb_jd(epoch: datetime | str, seconds=0.0) -> tuple[np.ndarray, np.ndarray]:
    """Two-part Julian date (jd1, jd2) on TDB, the argument of JPL ephemerides.

    TDB - TT is ERFA's ``dtdb`` series at the geocentre (|TDB - TT| < 1.7 ms).
    """
    return _two_part(utc_time(epoch, seconds), "tdb")


def tdb_seconds_since_j2000(epoch: datetime | str, seconds=0.0) -> np.ndarray:
    """TDB seconds since J2000.0 (JD 2451545.0 TDB): scalar or (K,) float, ~1 us precision."""
    jd1, jd2 = tdb_jd(epoch, seconds)
    return ((jd1 - J2000_JD) + jd2) * DAY_S


def tai_minus_utc(epoch: datetime | str, seconds=0.0) -> np.ndarray:
    """TAI - UTC (leap seconds accumulated), s: scalar or (K,)."""
    t = utc_time(epoch, seconds)
    with _quiet():
        iy, im, iday, fd = erfa.jd2cal(t.utc.jd1, t.utc.jd2)
        return np.asarray(erfa.dat(iy, im, iday, fd), dtype=float)


@dataclass(frozen=True)
class EarthOrientation:
    """Earth orientation at a set of UTC times (all arrays share the times' shape).

    Attributes
    ----------
    ut1_minus_utc : float array, s
    xp, yp : float arrays, rad
        Polar motion (the CIP in the ITRS).
    tabulated : bool array
        True where the bundled IERS table covered the time; False where the offline fallback
        (UT1-UTC = 0, mean pole) was used.
    """

    ut1_minus_utc: np.ndarray
    xp: np.ndarray
    yp: np.ndarray
    tabulated: np.ndarray


def earth_orientation(epoch: datetime | str, seconds=0.0) -> EarthOrientation:
    """UT1-UTC and polar motion from the bundled IERS table, with the offline fallback outside it.

    epoch, seconds as in :func:`utc_time`; results have the shape of ``seconds``.
    """
    return _orientation_of(utc_time(epoch, seconds))


_CACHE_TRIED = False


def _eop_table():
    """astropy's Earth orientation table; the default one is loaded through :mod:`.iers_cache`
    (the same table, without re-parsing the IERS files in every process)."""
    global _CACHE_TRIED
    if not _CACHE_TRIED:
        _CACHE_TRIED = True
        from cistrack.astro import iers_cache

        iers_cache.install()
    return iers.earth_orientation_table.get()


def _orientation_of(t: Time) -> EarthOrientation:
    table = _eop_table()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        utc = t.utc
        dut1, st_u = table.ut1_utc(utc.jd1, utc.jd2, return_status=True)
        xp, yp, st_p = table.pm_xy(utc.jd1, utc.jd2, return_status=True)
    dut1 = np.asarray(u.Quantity(dut1, u.s).to_value(u.s), dtype=float)
    xp = np.asarray(u.Quantity(xp, u.arcsec).to_value(u.rad), dtype=float)
    yp = np.asarray(u.Quantity(yp, u.arcsec).to_value(u.rad), dtype=float)
    in_u = np.asarray(st_u) >= 0
    in_p = np.asarray(st_p) >= 0
    dut1 = np.where(in_u, dut1, 0.0)
    xp = np.where(in_p, xp, MEAN_POLE_ARCSEC[0] * _ARCSEC_RAD)
    yp = np.where(in_p, yp, MEAN_POLE_ARCSEC[1] * _ARCSEC_RAD)
    return EarthOrientation(dut1, xp, yp, in_u & in_p)


@dataclass(frozen=True)
class TimeScales:
    """One set of times on every scale: two-part Julian dates (jd1, jd2) and Earth orientation.

    Attributes: ``utc``, ``tt``, ``tdb``, ``ut1`` (each a pair of arrays shaped like the
    seconds) and ``orientation`` (:class:`EarthOrientation`; UT1 uses its UT1-UTC).
    """

    utc: tuple[np.ndarray, np.ndarray]
    tt: tuple[np.ndarray, np.ndarray]
    tdb: tuple[np.ndarray, np.ndarray]
    ut1: tuple[np.ndarray, np.ndarray]
    orientation: EarthOrientation


_KEPT_SCALES: dict[tuple, tuple[object, TimeScales]] = {}
_KEPT_LIMIT = 32


def _copied(sc: TimeScales) -> TimeScales:
    def pair(p: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        return p[0].copy(), p[1].copy()

    eo = sc.orientation
    return TimeScales(pair(sc.utc), pair(sc.tt), pair(sc.tdb), pair(sc.ut1),
                      EarthOrientation(eo.ut1_minus_utc.copy(), eo.xp.copy(), eo.yp.copy(), eo.tabulated.copy()))


def time_scales(epoch: datetime | str, seconds=0.0) -> TimeScales:
    """UTC, TT, TDB and UT1 Julian dates and the Earth orientation from one astropy ``Time``.

    The same numbers as :func:`tt_jd`, :func:`tdb_jd`, :func:`ut1_jd` and
    :func:`earth_orientation`, several times cheaper than calling them one by one. The last
    :data:`_KEPT_LIMIT` results are kept and returned again (as copies) for the same ``epoch``
    and ``seconds`` with the same Earth orientation table: a least-squares fit asks for the
    same observation times at every iteration.
    """
    try:
        s = np.asarray(seconds, dtype=float)
        key = (epoch, s.shape, s.tobytes())
        hash(key)
    except (TypeError, ValueError):
        return _time_scales(epoch, seconds)     # refused there, with the message for the culprit
    table = _eop_table()
    # the kept entry holds its table, so no later table can take that table's id
    kept = kept_or_evaluated(_KEPT_SCALES, (id(table), *key), _KEPT_LIMIT,
                             lambda: (table, _time_scales(epoch, s)))
    return _copied(kept[1])


def _time_scales(epoch: datetime | str, seconds) -> TimeScales:
    t = utc_time(epoch, seconds)

    def pair(x) -> tuple[np.ndarray, np.ndarray]:
        return np.asarray(x.jd1, dtype=float), np.asarray(x.jd2, dtype=float)

    with _quiet():
        eo = _orientation_of(t)
        utc, tt, tdb = pair(t.utc), pair(t.tt), pair(t.tdb)
        t.delta_ut1_utc = eo.ut1_minus_utc
        ut1 = pair(t.ut1)
    return TimeScales(utc, tt, tdb, ut1, eo)


def ut1_jd(epoch: datetime | str, seconds=0.0,
           orientation: EarthOrientation | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Two-part Julian date (jd1, jd2) on UT1, from UT1-UTC of :func:`earth_orientation`.

    Pass ``orientation`` to reuse (or override) the Earth orientation for these times.
    """
    t = utc_time(epoch, seconds)
    eo = orientation if orientation is not None else earth_orientation(epoch, seconds)
    with _quiet():
        t.delta_ut1_utc = eo.ut1_minus_utc
        out = t.ut1
        return np.asarray(out.jd1, dtype=float), np.asarray(out.jd2, dtype=float)
