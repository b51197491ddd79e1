"""An independent reference for the ephemeris dynamics: scipy's DOP853 at tight tolerance in km
and seconds, the ephemeris read straight through jplephem (not cistrack's tables or reader), and a
right-hand side written separately in numpy (third-body terms in Battin's form)."""
from __future__ import annotations

import de421
import numpy as np
from jplephem.ephem import Ephemeris
from scipy.integrate import solve_ivp

_EPH = Ephemeris(de421)
DAY = 86400.0
_CONV = _EPH.AU ** 3 / DAY ** 2
GM_EARTH = _EPH.GMB * _CONV * _EPH.EMRAT / (1.0 + _EPH.EMRAT)
GM_MOON = _EPH.GMB * _CONV / (1.0 + _EPH.EMRAT)
GM_SUN = _EPH.GMS * _CONV


def moon_sun(jd: float, jd2: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Geocentric Moon and Sun, km, at TDB Julian date ``jd + jd2`` (read by jplephem; the
    two-part date keeps the time exact to microseconds)."""
    moon = np.reshape(_EPH.position("moon", jd, jd2), 3)
    emb = np.reshape(_EPH.position("earthmoon", jd, jd2), 3)
    sun = np.reshape(_EPH.position("sun", jd, jd2), 3)
    earth = emb - moon / (1.0 + _EPH.EMRAT)
    return moon, sun - earth


def _third_body(r: np.ndarray, s: np.ndarray, gm: float) -> np.ndarray:
    """gm ((s - r)/|s - r|^3 - s/|s|^3) without cancellation (Battin's f(q))."""
    d = r - s
    q = np.dot(r, r - 2.0 * s) / np.dot(s, s)
    fq = q * (3.0 + 3.0 * q + q * q) / (1.0 + (1.0 + q) ** 1.5)
    return -gm / np.linalg.norm(d) ** 3 * (r + fq * s)


def rhs(jd0: tuple[float, float], sun: bool = True):
    """Right-hand side in km, s for TDB epoch ``jd0`` = (jd1, jd2) of t = 0."""
    def f(t, y):
        r = y[:3]
        moon, sunp = moon_sun(jd0[0], jd0[1] + t / DAY)
        a = -GM_EARTH * r / np.linalg.norm(r) ** 3 + _third_body(r, moon, GM_MOON)
        if sun:
            a = a + _third_body(r, sunp, GM_SUN)
        return np.concatenate([y[3:], a])
    return f


def propagate_km(state_km: np.ndarray, jd0: tuple[float, float], seconds: np.ndarray, sun: bool = True,
                 rtol: float = 1e-13, atol: float = 1e-9) -> np.ndarray:
    """GCRS state (6,) km, km/s at TDB ``jd0`` (two parts) -> states (K, 6) at ``seconds`` after it."""
    sol = solve_ivp(rhs(jd0, sun), (0.0, float(seconds[-1])), np.asarray(state_km, float),
                    method="DOP853", rtol=rtol, atol=atol, t_eval=seconds)
    assert sol.success, sol.message
    return sol.y.T
