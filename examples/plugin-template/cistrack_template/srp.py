"""Earth–Moon CR3BP with a cannonball solar radiation pressure (SRP) acceleration.

The Sun is far away in the Earth–Moon plane and turns clockwise in the synodic frame at
``SUN_RATE`` (the synodic rate of the Sun relative to the rotating frame, nondimensional). The
SRP acceleration points away from the Sun with magnitude

    a = P_sun * C_r * (A / m)        P_sun = 4.56e-6 N/m^2 at 1 au,

converted to LU/TU^2. The equations of motion are written once as a numba function; cistrack's
compiled-dynamics base class supplies per-particle adaptive propagation, impacts on the Earth
and the Moon, backward propagation and input checks.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from cistrack import units
from cistrack.api import Body, CompiledDynamics, check_nonnegative, check_range
from cistrack.astro.primaries import MU_EARTH_MOON, earth_moon_primaries

__all__ = ["CR3BPSolarPressure", "srp_acceleration_lu_tu2", "SOLAR_PRESSURE_N_M2", "SUN_RATE"]

SOLAR_PRESSURE_N_M2 = 4.56e-6
"""Solar radiation pressure on a perfect absorber at 1 au, N/m^2."""
SUN_RATE = -0.925195985
"""Angular rate of the Sun direction in the synodic frame, rad/TU (clockwise)."""


def srp_acceleration_lu_tu2(area_to_mass_m2_per_kg: float, reflectivity: float) -> float:
    """SRP acceleration magnitude, LU/TU^2, for A/m in m^2/kg and C_r (dimensionless)."""
    a_km_s2 = SOLAR_PRESSURE_N_M2 * reflectivity * area_to_mass_m2_per_kg / 1000.0
    return a_km_s2 * units.TU_S**2 / units.LU_KM


@njit(cache=True)
def cr3bp_srp_rhs(t, y, p, out):
    """y (6,) [LU, VU] at t [TU] -> out (6,) [VU, VU/TU]; p = [mu, a_srp, sun_angle0, sun_rate]."""
    mu = p[0]
    xe = y[0] + mu
    xm = y[0] - 1.0 + mu
    yz2 = y[1] * y[1] + y[2] * y[2]
    r1s = xe * xe + yz2
    r2s = xm * xm + yz2
    c1 = (1.0 - mu) / (r1s * np.sqrt(r1s))
    c2 = mu / (r2s * np.sqrt(r2s))
    ang = p[2] + p[3] * t
    out[0] = y[3]
    out[1] = y[4]
    out[2] = y[5]
    out[3] = y[0] + 2.0 * y[4] - c1 * xe - c2 * xm - p[1] * np.cos(ang)
    out[4] = y[1] - 2.0 * y[3] - (c1 + c2) * y[1] - p[1] * np.sin(ang)
    out[5] = -(c1 + c2) * y[2]


class CR3BPSolarPressure(CompiledDynamics):
    """Earth–Moon CR3BP plus solar radiation pressure on a cannonball spacecraft.

    Parameters
    ----------
    area_to_mass_m2_per_kg : float
        Sun-facing area over mass, m^2/kg (0 gives the plain CR3BP).
    reflectivity : float
        Radiation pressure coefficient C_r, 1 (absorbing) to 2 (mirror).
    sun_angle_deg : float
        Direction of the Sun in the synodic x-y plane at t = 0, degrees from +x.
    mu : float
        Earth–Moon mass ratio.
    rtol, atol : float
        Per-particle integration tolerances (nondimensional).
    """

    rhs = cr3bp_srp_rhs

    def __init__(self, area_to_mass_m2_per_kg: float = 0.01, reflectivity: float = 1.3,
                 sun_angle_deg: float = 0.0, mu: float = MU_EARTH_MOON, rtol: float = 1e-10,
                 atol: float = 1e-12):
        self.area_to_mass_m2_per_kg = check_nonnegative(self, "area_to_mass_m2_per_kg", area_to_mass_m2_per_kg)
        self.reflectivity = check_range(self, "reflectivity", reflectivity, 1.0, 2.0)
        self.sun_angle_deg = check_range(self, "sun_angle_deg", sun_angle_deg, -360.0, 360.0)
        self.mu = check_range(self, "mu", mu, 0.0, 0.5, lo_open=True)
        self.rtol = check_range(self, "rtol", rtol, 1e-14, 1e-3)
        self.atol = check_range(self, "atol", atol, 1e-18, 1e-3)

    def params_vector(self) -> np.ndarray:
        a = srp_acceleration_lu_tu2(self.area_to_mass_m2_per_kg, self.reflectivity)
        return np.array([self.mu, a, np.radians(self.sun_angle_deg), SUN_RATE])

    @property
    def primaries(self) -> tuple[Body, ...]:
        """Earth and Moon with their mass fractions and radii (also the impact spheres)."""
        return earth_moon_primaries(self.mu)
