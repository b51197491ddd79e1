"""Independent reference for the real-sky tests: astropy's own observer, Earth ephemeris,
light-time iteration and ICRS -> AltAz transform (no cistrack.astro.sky or cistrack.astro.observer code)."""
from __future__ import annotations

import warnings

import numpy as np
from astropy import units as u
from astropy.coordinates import (AltAz, CartesianRepresentation, EarthLocation, ICRS, SkyCoord,
                                 get_body_barycentric_posvel)
from astropy.time import Time, TimeDelta

C_KMS = 299_792.458


def astropy_times(epoch: str, seconds: np.ndarray, ut1_minus_utc: np.ndarray) -> Time:
    t = Time(epoch.replace("Z", ""), scale="utc") + TimeDelta(seconds, format="sec")
    t.delta_ut1_utc = ut1_minus_utc
    return t


def location(lat_deg: float, lon_deg: float, height_m: float) -> EarthLocation:
    return EarthLocation.from_geodetic(lon_deg * u.deg, lat_deg * u.deg, height_m * u.m)


def observer_gcrs(loc: EarthLocation, t: Time) -> tuple[np.ndarray, np.ndarray]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        p, v = loc.get_gcrs_posvel(t)
    return p.xyz.to_value(u.km).T, v.xyz.to_value(u.km / u.s).T


def retarded_barycentric(loc: EarthLocation, t: Time, r_km: np.ndarray, v_kms: np.ndarray):
    """Barycentric target position at t - tau and observer position at t, km (N, 3) each.

    The target moves on the straight line r + v (t' - t) about the geocentre; the Earth's
    barycentric position is evaluated at t - tau itself (not linearised)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        obs = get_body_barycentric_posvel("earth", t)[0].xyz.to_value(u.km).T + observer_gcrs(loc, t)[0]
        tau = np.zeros(r_km.shape[0])
        for _ in range(6):
            earth = get_body_barycentric_posvel("earth", t - TimeDelta(tau, format="sec"))[0]
            target = earth.xyz.to_value(u.km).T + r_km - v_kms * tau[:, None]
            tau = np.linalg.norm(target - obs, axis=1) / C_KMS
    return target, obs


def astrometric_radec(loc, t, r_km, v_kms):
    target, obs = retarded_barycentric(loc, t, r_km, v_kms)
    p = target - obs
    return np.mod(np.arctan2(p[:, 1], p[:, 0]), 2 * np.pi), np.arctan2(p[:, 2], np.hypot(p[:, 0], p[:, 1]))


def apparent_altaz(loc, t, r_km, v_kms, pressure_hpa, temperature_c, humidity, wavelength_um):
    target, _ = retarded_barycentric(loc, t, r_km, v_kms)
    frame = AltAz(obstime=t, location=loc, pressure=pressure_hpa * u.hPa,
                  temperature=temperature_c * u.deg_C, relative_humidity=humidity,
                  obswl=wavelength_um * u.micron)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        out = SkyCoord(ICRS(CartesianRepresentation(target.T * u.km))).transform_to(frame)
    return out.az.rad, out.alt.rad
