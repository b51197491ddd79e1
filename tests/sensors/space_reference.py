"""An independent reference for the space telescope's geometry: scipy's DOP853 at tight
tolerance for the observer (and for the target over the light time), rotations to the inertial
frame written out by hand, and the light time found by iterating on exact back-propagations of
the target. Nothing here calls cistrack's propagators, frames or sensors."""
from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from reference_cr3bp import MU, cr3bp_rhs

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
