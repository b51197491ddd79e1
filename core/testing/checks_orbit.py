"""Conformance checks for reference orbits (kind "orbit": data objects, not classes)."""
from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from cistrack.interfaces.orbit import ReferenceOrbit
from cistrack.testing.check_support import require, round_trip
from cistrack.testing.reference_dynamics import cr3bp_derivatives

__all__ = ["ORBIT_CHECKS"]

CLOSURE_TOL = 1e-6
"""Largest |x(T) - x(0)| (LU, VU) accepted for a periodic orbit after one period."""


def check_fields(orbit) -> None:
    require(isinstance(orbit, ReferenceOrbit), f"{type(orbit).__name__} is not a cistrack.interfaces.ReferenceOrbit")
    require(isinstance(orbit.name, str) and orbit.name, "name must be a non-empty str")
    x = np.asarray(orbit.state)
    require(x.shape == (6,) and np.issubdtype(x.dtype, np.floating) and np.all(np.isfinite(x)),
            f"state must be a finite (6,) float array, got {x.dtype} {x.shape}")
    require(np.linalg.norm(x[:3]) < 10.0, f"state position {x[:3]} is beyond 10 LU: is it in km instead of LU?")
    require(0.0 < float(orbit.mu) <= 0.5, f"mu = {orbit.mu} must lie in (0, 0.5]")
    if orbit.period is not None:
        require(np.isfinite(orbit.period) and orbit.period > 0, f"period = {orbit.period} must be > 0 TU or None")
    require(isinstance(orbit.description, str), "description must be a str")


def check_periodic_orbit_closes(orbit) -> None:
    """A periodic orbit returns to its state after one period (CR3BP of its own mu, DOP853
    at 1e-12) to within 1e-6."""
    if orbit.period is None:
        return
    mu = float(orbit.mu)
    sol = solve_ivp(lambda t, y: cr3bp_derivatives(y[None], mu)[0], (0.0, float(orbit.period)),
                    np.asarray(orbit.state, dtype=float), method="DOP853", rtol=1e-12, atol=1e-12)
    require(sol.success, f"integrating one period failed: {sol.message}")
    miss = float(np.max(np.abs(sol.y[:, -1] - orbit.state)))
    require(miss < CLOSURE_TOL, f"after one period ({orbit.period} TU) the orbit misses its initial state by "
                                f"{miss:.3g} (LU/VU); ship differentially corrected values")


def check_picklable(orbit) -> None:
    other = round_trip(orbit)
    require(np.array_equal(other.state, orbit.state) and other.name == orbit.name, "unpickling changed the orbit")


ORBIT_CHECKS = [
    ("fields", check_fields),
    ("periodic_orbit_closes", check_periodic_orbit_closes),
    ("picklable", check_picklable),
]
