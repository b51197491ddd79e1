"""JPL DE421 planetary and lunar ephemeris: Earth-centred Moon and Sun, and kernel tables.

The ephemeris is JPL's DE421 (Folkner, Williams & Boggs 2009, 1900-2050) as shipped in the PyPI
package ``de421`` (Chebyshev coefficient arrays, MIT licence) and read through ``jplephem``'s
reader for that layout: no file is ever downloaded at run time.

Axes are ICRF (the GCRS axes for an Earth-centred vector); positions are km, velocities km/s, and
time is TDB, given as a Julian date split in two parts ``(jd1, jd2)`` for precision (see
:mod:`cistrack.astro.timescales` for UTC -> TDB).

DE421's series (record length, coefficients per axis): ``moon`` = geocentric Moon (4 d, 13),
``earthmoon`` = Earth-Moon barycentre w.r.t. the solar-system barycentre (16 d, 13), ``sun`` =
Sun w.r.t. the solar-system barycentre (16 d, 11). The Earth is ``earthmoon - moon / (1 + EMRAT)``,
so the geocentric Sun is ``sun - earthmoon + moon / (1 + EMRAT)``.

For compiled right-hand sides, :meth:`DE421.series` cuts the coefficient records covering an
interval out of a series as a :class:`ChebyshevSeries` (times in seconds relative to a chosen TDB
origin), and :func:`chebyshev_position` / :func:`chebyshev_state` evaluate one inside numba code
exactly as the reader does (Clenshaw's recurrence), so a kernel sees the ephemeris itself, not a
refit of it. Importing this module loads neither numba nor jplephem.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from cistrack.lazy import lazy_njit

__all__ = ["DE421", "ChebyshevSeries", "chebyshev_position", "chebyshev_state", "de421",
           "DAY_S", "J2000_JD", "check_de421_epoch", "DE421_YEARS"]

DAY_S: float = 86_400.0
J2000_JD: float = 2_451_545.0
"""Julian date of J2000.0 (TDB); the origin of ``tdb seconds since J2000``."""


@dataclass(frozen=True)
class ChebyshevSeries:
    """Consecutive Chebyshev records of one body's position, uniform record length.

    Attributes
    ----------
    start_s : float
        Start of the first record, seconds (TDB) after the chosen time origin.
    length_s : float
        Length of every record, seconds.
    coefficients : (R, 3, C) float
        Position coefficients, km: record, axis (x, y, z), Chebyshev order.
    """

    start_s: float
    length_s: float
    coefficients: np.ndarray

    def position(self, t_s) -> np.ndarray:
        """Positions at times ``t_s`` ((N,) or scalar, s after the origin) -> (N, 3) km."""
        t = np.atleast_1d(np.asarray(t_s, dtype=float))
        out = np.empty((t.size, 3))
        for i, ti in enumerate(t):
            self._check(ti)
            chebyshev_position(self.start_s, self.length_s, self.coefficients, ti, out[i])
        return out

    def state(self, t_s) -> tuple[np.ndarray, np.ndarray]:
        """Positions (N, 3) km and velocities (N, 3) km/s at ``t_s`` (s after the origin)."""
        t = np.atleast_1d(np.asarray(t_s, dtype=float))
        pos = np.empty((t.size, 3))
        vel = np.empty((t.size, 3))
        for i, ti in enumerate(t):
            self._check(ti)
            chebyshev_state(self.start_s, self.length_s, self.coefficients, ti, pos[i], vel[i])
        return pos, vel

    @property
    def end_s(self) -> float:
        """End of the last record, s after the origin."""
        return self.start_s + self.length_s * self.coefficients.shape[0]

    def _check(self, t: float) -> None:
        if not (self.start_s <= t <= self.end_s):
            raise ValueError(f"time {t:.3f} s lies outside the series' records "
                             f"[{self.start_s:.3f}, {self.end_s:.3f}] s")


@lazy_njit(cache=True)
def chebyshev_position(start_s, length_s, coefficients, t_s, out):
    """Position (3,) km of a Chebyshev series (R, 3, C) at ``t_s`` into ``out``.

    Compiled on first call (:func:`cistrack.lazy.lazy_njit`); compiled code calls
    ``chebyshev_position.dispatcher``.

    Times outside the records use the nearest record (extrapolation); callers size the series
    to cover their interval.
    """
    nrec = coefficients.shape[0]
    ncoef = coefficients.shape[2]
    k = int(np.floor((t_s - start_s) / length_s))
    if k < 0:
        k = 0
    elif k > nrec - 1:
        k = nrec - 1
    x = 2.0 * (t_s - start_s - k * length_s) / length_s - 1.0
    x2 = 2.0 * x
    for a in range(3):
        b1 = 0.0
        b2 = 0.0
        for j in range(ncoef - 1, 0, -1):
            b0 = x2 * b1 - b2 + coefficients[k, a, j]
            b2 = b1
            b1 = b0
        out[a] = x * b1 - b2 + coefficients[k, a, 0]


@lazy_njit(cache=True)
def chebyshev_state(start_s, length_s, coefficients, t_s, pos, vel):
    """Position (3,) km and velocity (3,) km/s of a Chebyshev series at ``t_s`` (compiled on
    first call; compiled code calls ``chebyshev_state.dispatcher``)."""
    nrec = coefficients.shape[0]
    ncoef = coefficients.shape[2]
    k = int(np.floor((t_s - start_s) / length_s))
    if k < 0:
        k = 0
    elif k > nrec - 1:
        k = nrec - 1
    x = 2.0 * (t_s - start_s - k * length_s) / length_s - 1.0
    scale = 2.0 / length_s
    for a in range(3):
        t0 = 1.0
        t1 = x
        d0 = 0.0
        d1 = 1.0
        p = coefficients[k, a, 0] + coefficients[k, a, 1] * x
        v = coefficients[k, a, 1]
        for j in range(2, ncoef):
            t2 = 2.0 * x * t1 - t0
            d2 = 2.0 * x * d1 - d0 + 2.0 * t1
            p += coefficients[k, a, j] * t2
            v += coefficients[k, a, j] * d2
            t0 = t1
            t1 = t2
            d0 = d1
            d1 = d2
        pos[a] = p
        vel[a] = v * scale


def _as_jd(jd1, jd2) -> tuple[np.ndarray, np.ndarray, bool]:
    a = np.asarray(jd1, dtype=float)
    b = np.asarray(jd2, dtype=float)
    scalar = a.ndim == 0 and b.ndim == 0
    a, b = np.broadcast_arrays(np.atleast_1d(a), np.atleast_1d(b))
    return a.reshape(-1), b.reshape(-1), scalar


class DE421:
    """JPL DE421 read from the ``de421`` package through ``jplephem`` (offline).

    Attributes (from the ephemeris' own constants)
    ----------
    gm_earth_km3s2, gm_moon_km3s2, gm_sun_km3s2 : float
        Gravitational parameters, km^3/s^2.
    earth_radius_km : float
        DE421's Earth radius (6378.136 km), used with its J2.
    j2_earth : float
        DE421's Earth J2.
    au_km : float
        Astronomical unit, km.
    emrat : float
        Earth/Moon mass ratio.
    first_jd, last_jd : float
        TDB Julian dates covered (1899-07-29 to 2053-10-09).
    """

    def __init__(self) -> None:
        try:
            import de421 as _pkg
            from jplephem.ephem import Ephemeris
        except ImportError as exc:  # pragma: no cover - both are install requirements
            raise ImportError("cistrack.astro.ephemeris needs the packages 'jplephem' and 'de421' "
                              f"(pip install jplephem de421): {exc}") from None
        self._eph = Ephemeris(_pkg)
        e = self._eph
        conv = e.AU ** 3 / DAY_S ** 2
        gmb = e.GMB * conv
        self.emrat = float(e.EMRAT)
        self.gm_earth_km3s2 = float(gmb * e.EMRAT / (1.0 + e.EMRAT))
        self.gm_moon_km3s2 = float(gmb / (1.0 + e.EMRAT))
        self.gm_sun_km3s2 = float(e.GMS * conv)
        self.au_km = float(e.AU)
        self.earth_radius_km = float(e.RE)
        self.j2_earth = float(e.J2E)
        self.first_jd = float(e.jalpha)
        self.last_jd = float(e.jomega)

    @property
    def earth_share(self) -> float:
        """1 / (1 + EMRAT): the Earth's offset from the barycentre per unit geocentric Moon."""
        return 1.0 / (1.0 + self.emrat)

    def _check_jd(self, a: np.ndarray, b: np.ndarray) -> None:
        jd = a + b
        if not np.all(np.isfinite(jd)):
            raise ValueError("DE421: TDB Julian dates must be finite")
        if np.any(jd < self.first_jd) or np.any(jd > self.last_jd):
            raise ValueError(f"DE421 covers TDB JD {self.first_jd} to {self.last_jd} "
                             f"(1899-2053); got {jd.min():.3f} .. {jd.max():.3f}")

    def _raw(self, name: str, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        pos, vel = self._eph.position_and_velocity(name, a, b)
        return np.asarray(pos).T, np.asarray(vel).T / DAY_S

    def moon_acceleration(self, jd1, jd2=0.0) -> np.ndarray:
        """Second time derivative of the geocentric Moon at TDB ``jd1 + jd2``: (N, 3) km/s^2.

        Differentiates DE421's Chebyshev series twice (used for the rotation rate of the real
        Earth-Moon frame about its x axis). Scalar dates give a (3,) array.
        """
        a, b, scalar = _as_jd(jd1, jd2)
        self._check_jd(a, b)
        sets = self._eph.load("moon")
        nset, _, ncoef = sets.shape
        days = (self._eph.jomega - self._eph.jalpha) / nset
        k, off = np.divmod((a - self._eph.jalpha) + b, days)
        k = np.minimum(k.astype(np.int64), nset - 1)
        off = (a - self._eph.jalpha) + b - k * days
        x = 2.0 * off / days - 1.0
        t = np.zeros((ncoef, x.size))
        d1 = np.zeros_like(t)
        d2 = np.zeros_like(t)
        t[0] = 1.0
        t[1] = x
        d1[1] = 1.0
        for n in range(2, ncoef):
            t[n] = 2.0 * x * t[n - 1] - t[n - 2]
            d1[n] = 2.0 * x * d1[n - 1] - d1[n - 2] + 2.0 * t[n - 1]
            d2[n] = 2.0 * x * d2[n - 1] - d2[n - 2] + 4.0 * d1[n - 1]
        acc = np.einsum("kac,ck->ka", sets[k], d2) * (2.0 / (days * DAY_S)) ** 2
        return acc[0] if scalar else acc

    def moon(self, jd1, jd2=0.0) -> tuple[np.ndarray, np.ndarray]:
        """Geocentric Moon at TDB ``jd1 + jd2``: position (N, 3) km, velocity (N, 3) km/s.

        Scalar dates give (3,) arrays.
        """
        a, b, scalar = _as_jd(jd1, jd2)
        self._check_jd(a, b)
        pos, vel = self._raw("moon", a, b)
        return (pos[0], vel[0]) if scalar else (pos, vel)

    def sun(self, jd1, jd2=0.0) -> tuple[np.ndarray, np.ndarray]:
        """Geocentric Sun at TDB ``jd1 + jd2``: position (N, 3) km, velocity (N, 3) km/s."""
        a, b, scalar = _as_jd(jd1, jd2)
        self._check_jd(a, b)
        ps, vs = self._raw("sun", a, b)
        pb, vb = self._raw("earthmoon", a, b)
        pm, vm = self._raw("moon", a, b)
        f = self.earth_share
        pos = ps - pb + f * pm
        vel = vs - vb + f * vm
        return (pos[0], vel[0]) if scalar else (pos, vel)

    def series(self, name: str, origin_jd: tuple[float, float], start_s: float,
               end_s: float) -> ChebyshevSeries:
        """The records of series ``name`` covering ``[start_s, end_s]`` s after ``origin_jd``.

        Parameters
        ----------
        name : {"moon", "sun", "earthmoon"}
            A DE421 series (see the module docstring for what each holds).
        origin_jd : (float, float)
            TDB Julian date (two parts) that times are counted from.
        start_s, end_s : float
            Interval to cover, TDB seconds after the origin (either order).

        Returns a :class:`ChebyshevSeries` whose times are seconds after ``origin_jd``; one extra
        record either side is included.
        """
        if name not in ("moon", "sun", "earthmoon"):
            raise ValueError(f"DE421 series must be one of 'moon', 'sun', 'earthmoon', got {name!r}")
        lo, hi = sorted((float(start_s), float(end_s)))
        o1, o2 = float(origin_jd[0]), float(origin_jd[1])
        for s in (lo, hi):
            self._check_jd(np.array([o1]), np.array([o2 + s / DAY_S]))
        sets = self._eph.load(name)
        nset = sets.shape[0]
        days = (self._eph.jomega - self._eph.jalpha) / nset
        # days from the ephemeris start to the origin, kept in two parts for precision
        base_days = (o1 - self._eph.jalpha) + o2
        k0 = int(np.floor((base_days + lo / DAY_S) / days)) - 1
        k1 = int(np.floor((base_days + hi / DAY_S) / days)) + 1
        k0 = max(k0, 0)
        k1 = min(k1, nset - 1)
        coef = np.ascontiguousarray(sets[k0:k1 + 1], dtype=np.float64)
        start = ((self._eph.jalpha - o1) - o2 + k0 * days) * DAY_S
        return ChebyshevSeries(start_s=float(start), length_s=float(days * DAY_S), coefficients=coef)


@lru_cache(maxsize=1)
def de421() -> DE421:
    """The process-wide DE421 reader (loaded once; series are read lazily)."""
    return DE421()


DE421_YEARS = (1900, 2052)
"""The whole UTC years cistrack takes from DE421 (first, last): the ephemeris spans 1899-07-29 to
2053-10-09 (Folkner, Williams & Boggs 2009)."""


def check_de421_epoch(owner, value, year: int) -> None:
    """Refuse a component's ``epoch`` parameter (``value``, in ``year``) outside DE421's whole
    years (:data:`DE421_YEARS`), with the component's ParameterError (``owner._fail``)."""
    first, last = DE421_YEARS
    if not first <= year <= last:
        owner._fail("epoch", value, f"must lie within DE421's span (years {first} to {last}; a scenario's top-level "
                                    "'epoch' sets it)")
