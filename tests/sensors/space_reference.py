"""An independent reference for the space telescope's geometry: scipy's DOP853 at tight
tolerance for the observer (and for the target over the light time), rotations to the inertial
frame written out by hand, and the light time found by iterating on exact back-propagations of
the target. Nothing here calls cistrack's propagators, frames or sensors."""
from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from reference_cr3bp import cr3bp_rhs

LU_KM, TU_S = 384_400.0, 375_149.0
C_KMS = 299_792.458


def cr3bp_state(x0: np.ndarray, t0: float, t: float) -> np.ndarray:
    """CR3BP state (6,) at t from x0 at t0 (TU), rtol 1e-13."""
    if t == t0:
        return np.array(x0, dtype=float)
    sol = solve_ivp(cr3bp_rhs, (t0, t), x0, method="DOP853", rtol=1e-13, atol=1e-16)
    assert sol.success, sol.message
    return sol.y[:, -1]


def _rz(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def cr3bp_inertial_km(x: np.ndarray, t: float, phase_rad: float) -> np.ndarray:
    """Barycentric inertial position (3,) km of a synodic position: x axis at angle phase + t."""
    return _rz(phase_rad + t) @ np.asarray(x[:3]) * LU_KM


def cr3bp_radec(target_at_t: np.ndarray, observer_x0: np.ndarray, observer_t0: float, t: float,
                phase_rad: float = 0.0, light_time: bool = True) -> tuple[float, float]:
    """RA, Dec (rad) of a target whose synodic state at t is ``target_at_t``, from an observer
    passing ``observer_x0`` at ``observer_t0``: p = R(t - tau) r_t(t - tau) - R(t) r_o(t)."""
    obs = cr3bp_inertial_km(cr3bp_state(observer_x0, observer_t0, t), t, phase_rad)
    tau = 0.0
    for _ in range(6 if light_time else 1):
        back = cr3bp_state(target_at_t, t, t - tau / TU_S) if tau > 0 else target_at_t
        p = cr3bp_inertial_km(back, t - tau / TU_S, phase_rad) - obs
        tau = np.linalg.norm(p) / C_KMS if light_time else 0.0
    return float(np.mod(np.arctan2(p[1], p[0]), 2 * np.pi)), float(np.arctan2(p[2], np.hypot(p[0], p[1])))


def angle_between(ra1, dec1, ra2, dec2) -> float:
    """Great-circle angle (rad) between two directions, accurate for tiny angles (haversine)."""
    h = np.sin((dec2 - dec1) / 2) ** 2 + np.cos(dec1) * np.cos(dec2) * np.sin((ra2 - ra1) / 2) ** 2
    return float(2 * np.arcsin(np.sqrt(h)))


# -- ephemeris model: GCRS from jplephem, the real Earth-Moon frame built by hand -------------

def tdb_jd(epoch_utc: str) -> tuple[float, float]:
    """TDB Julian date (two parts) of a UTC time, by astropy."""
    from astropy.time import Time
    t = Time(epoch_utc.replace("Z", ""), scale="utc").tdb
    return float(t.jd1), float(t.jd2)


def _moon(eph, jd1: float, jd2: float):
    """Geocentric Moon position (3,) km and velocity (3,) km/s from jplephem."""
    p, v = eph.position_and_velocity("moon", jd1, jd2)
    return np.reshape(p, 3), np.reshape(v, 3) / 86400.0


def synodic_to_gcrs_by_hand(x: np.ndarray, jd: tuple[float, float], t_s: float) -> np.ndarray:
    """Synodic state (6,) LU, VU of the real Earth-Moon frame -> GCRS (6,) km, km/s: x axis to the
    Moon, z along the Moon's orbital angular momentum, origin at the barycentre, axes turning at
    omega = (h / d^2) z + (d (a . z) / h) x (a: the Moon's acceleration, central differences)."""
    from dynamics.reference_ephemeris import _EPH as eph
    jd1, jd2 = jd[0], jd[1] + t_s / 86400.0
    r, v = _moon(eph, jd1, jd2)
    dt = 1.0
    a = (_moon(eph, jd1, jd2 + dt / 86400.0)[1] - _moon(eph, jd1, jd2 - dt / 86400.0)[1]) / (2 * dt)
    d = np.linalg.norm(r)
    hv = np.cross(r, v)
    h = np.linalg.norm(hv)
    ex, ez = r / d, hv / h
    rot = np.stack([ex, np.cross(ez, ex), ez], axis=1)
    omega = h / d ** 2 * ez + d * np.dot(a, ez) / h * ex
    share = 1.0 / (1.0 + eph.EMRAT)
    rho = rot @ (np.asarray(x[:3]) * LU_KM)
    vel = share * v + rot @ (np.asarray(x[3:]) * LU_KM / TU_S) + np.cross(omega, rho)
    return np.concatenate([share * r + rho, vel])


def _earth_bary_km(jd1: float, jd2: float) -> np.ndarray:
    from dynamics.reference_ephemeris import _EPH as eph
    emb = np.reshape(eph.position("earthmoon", jd1, jd2), 3)
    moon = np.reshape(eph.position("moon", jd1, jd2), 3)
    return emb - moon / (1.0 + eph.EMRAT)


def ephemeris_radec(target_at_t: np.ndarray, observer_x0: np.ndarray, observer_t0: float, t: float,
                    epoch_utc: str) -> tuple[float, float]:
    """Astrometric RA, Dec (rad, ICRF) of a target (synodic state at t) from an observer passing
    ``observer_x0`` at ``observer_t0`` (TU), under Earth, Moon and Sun point masses (DE421):
    p = (r_t(t - tau) + E(t - tau)) - (r_o(t) + E(t)), E the barycentric geocentre."""
    from dynamics.reference_ephemeris import propagate_km
    jd = tdb_jd(epoch_utc)
    t0_s, t_s = observer_t0 * TU_S, t * TU_S
    obs0 = synodic_to_gcrs_by_hand(observer_x0, jd, t0_s)
    jd_obs0 = (jd[0], jd[1] + t0_s / 86400.0)
    obs = propagate_km(obs0, jd_obs0, np.array([t_s - t0_s]))[-1] if t_s > t0_s else obs0
    tgt = synodic_to_gcrs_by_hand(target_at_t, jd, t_s)
    jd_t = (jd[0], jd[1] + t_s / 86400.0)
    e_now = _earth_bary_km(*jd_t)
    tau = 0.0
    for _ in range(5):
        back = propagate_km(tgt, jd_t, np.array([-tau]))[-1] if tau > 0 else tgt
        p = back[:3] + _earth_bary_km(jd_t[0], jd_t[1] - tau / 86400.0) - obs[:3] - e_now
        tau = np.linalg.norm(p) / C_KMS
    return float(np.mod(np.arctan2(p[1], p[0]), 2 * np.pi)), float(np.arctan2(p[2], np.hypot(p[0], p[1])))
