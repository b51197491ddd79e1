"""Where a target near the Earth appears from a ground site: astrometric RA/Dec, apparent az/el.

Targets are given by geocentric positions r (km) and velocities v (km/s), GCRS axes, at the
observation time t (UTC instant of the observer clock). The observer comes from
:class:`cistrack.astro.observer.ObserverGeometry` at the same times.

Corrections (each one a switch in :class:`SkyCorrections`, each one named in
:meth:`SkyCorrections.applied`):

``light_time``
    The target is seen where it was at t - tau, with tau the light travel time solved in the
    barycentric frame (BCRS): the astrometric vector is
    ``p = r(t - tau) - r_obs(t) - v_earth * tau`` with ``|p| = c * tau``, the target's motion over
    tau taken as straight (tau < 1.5 s in cislunar space: the curvature error is below 1 cm).
    The ``- v_earth * tau`` term is the Earth's own barycentric motion during tau; it is what
    makes the result the ICRF *astrometric* place that MPC and ADES astrometry reports (reduced
    against catalogue stars, which carry the same aberration). Off: the geometric direction
    ``r(t) - r_obs(t)``.
``annual_aberration``, ``diurnal_aberration``
    Stellar aberration of the astrometric direction by the observer's barycentric velocity:
    the Earth's (annual, up to 20.5 arcsec) and the site's rotation (diurnal, up to 0.32 arcsec),
    relativistic formula of ``erfa.ab``. For a target near the Earth the annual term nearly
    cancels the ``- v_earth * tau`` part of the light time: keep both on together (or both off)
    for apparent places. Applies to az/el only; astrometric RA/Dec has no aberration.
``refraction``
    Atmospheric refraction of the elevation, the model ``A tan z + B tan^3 z`` with A, B from
    ``erfa.refco`` (pressure, temperature, humidity, wavelength) and one Newton step from
    vacuum to observed zenith distance. Good to about 1 arcsec above 15 deg elevation; below
    about 3 deg elevation the correction is held at its 3 deg value. Off by default (it needs the
    site's weather). Applies to az/el only.
``polar_motion``, ``ut1``
    Earth orientation in the observer position and in the Earth-fixed frame (see
    :mod:`cistrack.astro.observer`).

Angles rad (RA in [0, 2pi), azimuth North through East in [0, 2pi)), ranges km.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cistrack.astro.observer import C_KMS, ObserverState
from cistrack.lazy import LazyModule

erfa = LazyModule("erfa")  # on first use: a run without the real sky does not need ERFA

__all__ = ["SkyCorrections", "astrometric_vector", "astrometric_radec", "apparent_azel",
           "refract_elevation", "unrefract_elevation", "standard_pressure_hpa", "unit_vectors_gcrs"]

_TWO_PI = 2.0 * np.pi
_SIN_EL_MIN = np.sin(np.radians(3.0))


def standard_pressure_hpa(height_m: float) -> float:
    """Pressure of a standard atmosphere at ``height_m`` (hPa): 1013.25 exp(-h / 8434.5 m)."""
    return 1013.25 * float(np.exp(-float(height_m) / 8434.5))


@dataclass(frozen=True)
class SkyCorrections:
    """Which corrections a sky measurement applies, and the weather for refraction.

    Attributes: the switches of the module docstring, and ``pressure_hpa`` (None: standard
    atmosphere at the site height), ``temperature_c``, ``relative_humidity`` (0-1),
    ``wavelength_um`` for refraction.
    """

    light_time: bool = True
    annual_aberration: bool = True
    diurnal_aberration: bool = True
    refraction: bool = False
    polar_motion: bool = True
    ut1: bool = True
    pressure_hpa: float | None = None
    temperature_c: float = 10.0
    relative_humidity: float = 0.5
    wavelength_um: float = 0.55

    def applied(self) -> list[str]:
        """Names of the corrections that are on, in the order they are applied."""
        order = ("ut1", "polar_motion", "light_time", "annual_aberration", "diurnal_aberration",
                 "refraction")
        return [n for n in order if getattr(self, n)]


def astrometric_vector(r_km: np.ndarray, v_kms: np.ndarray, obs: ObserverState,
                       light_time: bool = True) -> np.ndarray:
    """Observer-to-target vector (N, 3) km, GCRS/ICRF axes: astrometric (BCRS light time) or geometric.

    r_km, v_kms : (N, 3) geocentric target position and velocity at the observation times;
    obs : observer state with K = N or K = 1 rows.
    """
    geo = r_km - obs.position_km
    if not light_time:
        return geo
    drift = v_kms + obs.earth_velocity_kms                       # (N, 3): p(tau) = geo - drift tau
    tau = np.linalg.norm(geo, axis=1) / C_KMS
    for _ in range(3):                                           # contraction factor |v|/c ~ 1e-4
        tau = np.linalg.norm(geo - drift * tau[:, None], axis=1) / C_KMS
    return geo - drift * tau[:, None]


def _ra_dec(p: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rho = np.linalg.norm(p, axis=1)
    ra = np.mod(np.arctan2(p[:, 1], p[:, 0]), _TWO_PI)
    ra = np.where(ra >= _TWO_PI, 0.0, ra)
    dec = np.arctan2(p[:, 2], np.hypot(p[:, 0], p[:, 1]))
    return ra, dec, rho


def astrometric_radec(r_km: np.ndarray, v_kms: np.ndarray, obs: ObserverState,
                      light_time: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Topocentric astrometric (ICRF) right ascension, declination (rad) and range (km): (N,) each.

    As MPC/ADES report optical astrometry: light time on, no aberration, no refraction.
    """
    return _ra_dec(astrometric_vector(r_km, v_kms, obs, light_time))


def _aberrate(p: np.ndarray, obs: ObserverState, annual: bool, diurnal: bool) -> np.ndarray:
    """Unit apparent directions (N, 3) from astrometric vectors p (N, 3)."""
    u = p / np.linalg.norm(p, axis=1)[:, None]
    if not (annual or diurnal):
        return u
    v = np.zeros_like(u)
    if annual:
        v = v + obs.earth_velocity_kms
    if diurnal:
        v = v + obs.velocity_kms
    beta = v / C_KMS
    bm1 = np.sqrt(1.0 - np.einsum("ni,ni->n", beta, beta))
    s = np.broadcast_to(obs.sun_distance_au, bm1.shape)
    return np.asarray(erfa.ab(u, beta, s, bm1), dtype=float)


def refract_elevation(el: np.ndarray, c: SkyCorrections, height_m: float) -> np.ndarray:
    """Observed elevation (N,) rad from vacuum elevation (N,) rad: A tan z + B tan^3 z, one Newton step.

    A, B from ``erfa.refco`` with the weather of ``c`` (``pressure_hpa`` None: standard
    atmosphere at ``height_m``).
    """
    p = standard_pressure_hpa(height_m) if c.pressure_hpa is None else c.pressure_hpa
    a, b = erfa.refco(p, c.temperature_c, c.relative_humidity, c.wavelength_um)
    s = np.maximum(np.sin(el), _SIN_EL_MIN)
    cz = np.maximum(np.cos(el), 1e-6)
    tz = cz / s                                                   # tan(zenith distance)
    w = b * tz * tz
    delta = (a + w) * tz / (1.0 + (a + 3.0 * w) / (s * s))
    return el + delta


def apparent_azel(r_km: np.ndarray, v_kms: np.ndarray, obs: ObserverState, neu_basis: np.ndarray,
                  corrections: SkyCorrections, height_m: float = 0.0,
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Apparent azimuth, elevation (rad) and astrometric range (km) at the site: (N,) each.

    neu_basis : (3, 3) site North/East/Up rows in the ITRS (``cistrack.astro.observer.neu_basis(site)``).
    """
    p = astrometric_vector(r_km, v_kms, obs, corrections.light_time)
    rho = np.linalg.norm(p, axis=1)
    u = _aberrate(p, obs, corrections.annual_aberration, corrections.diurnal_aberration)
    m = neu_basis @ obs.gcrs_to_itrs                               # (K, 3, 3) GCRS -> NEU
    neu = np.einsum("kij,kj->ki", m, u) if m.shape[0] == u.shape[0] else u @ m[0].T
    az = np.mod(np.arctan2(neu[:, 1], neu[:, 0]), _TWO_PI)
    az = np.where(az >= _TWO_PI, 0.0, az)
    el = np.arctan2(neu[:, 2], np.hypot(neu[:, 0], neu[:, 1]))
    if corrections.refraction:
        el = refract_elevation(el, corrections, height_m)
    return az, el, rho


def unrefract_elevation(el_obs: np.ndarray, c: SkyCorrections, height_m: float = 0.0) -> np.ndarray:
    """Vacuum elevation (N,) rad from observed elevation (N,) rad: :func:`refract_elevation` inverted
    by fixed-point iteration (the correction changes slowly with elevation)."""
    el = np.array(el_obs, dtype=float, copy=True)
    for _ in range(4):
        el = el_obs - (refract_elevation(el, c, height_m) - el)
    return el


def unit_vectors_gcrs(a: np.ndarray, b: np.ndarray, obs: ObserverState, neu_basis: np.ndarray,
                      corrections: SkyCorrections, azel: bool, height_m: float = 0.0) -> np.ndarray:
    """Directions (N, 3), GCRS axes, from the observer towards where targets measured at angles
    (a, b) (N,) rad are now, up to the target's own motion during the light time.

    azel: (azimuth, elevation) of :func:`apparent_azel`; refraction and aberration are undone
    (aberration to first order, error ~ (v/c)^2 ~ 1e-8 rad). Otherwise (RA, Dec) of
    :func:`astrometric_radec`. With light time on, the Earth's barycentric motion during the
    light time is added back exactly: p + v_earth tau = c tau (u + v_earth / c).
    """
    c = corrections
    if azel:
        if c.refraction:
            b = unrefract_elevation(b, c, height_m)
        cb = np.cos(b)
        neu = np.stack([cb * np.cos(a), cb * np.sin(a), np.sin(b)], axis=1)
        m = neu_basis @ obs.gcrs_to_itrs                                # GCRS -> NEU
        u = np.einsum("kji,kj->ki", m, neu) if m.shape[0] == neu.shape[0] else neu @ m[0]
        beta = np.zeros_like(u)
        if c.annual_aberration:
            beta = beta + obs.earth_velocity_kms / C_KMS
        if c.diurnal_aberration:
            beta = beta + obs.velocity_kms / C_KMS
        u = u - beta + np.einsum("ni,ni->n", u, beta)[:, None] * u
        u /= np.linalg.norm(u, axis=1)[:, None]
    else:
        cb = np.cos(b)
        u = np.stack([cb * np.cos(a), cb * np.sin(a), np.sin(b)], axis=1)
    if c.light_time:
        u = u + np.broadcast_to(obs.earth_velocity_kms / C_KMS, u.shape)
        u /= np.linalg.norm(u, axis=1)[:, None]
    return u
