"""The space telescope's RA/Dec agree with an independent reference (tests/sensors/space_reference.py):
1e-6 arcsec in the CR3BP, 0.01 arcsec in the ephemeris model."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.plugins.dynamics.orbit_catalog import ORBITS
from cistrack.plugins.sensors.space_telescope import SpaceTelescope
from cistrack.units import ARCSEC_RAD

from reference_cr3bp import cr3bp_rhs  # noqa: F401  (tests/ is on sys.path)
from sensors.space_reference import angle_between, cr3bp_radec, cr3bp_state

TARGETS = [("nrho-9-2", 0.3), ("nrho-9-2", 1.1), ("l2-lyapunov", 0.7), ("mirror-3-1", 2.0)]


@pytest.mark.parametrize("orbit, phase", [("dro-2-1", 0.25), ("l2-lyapunov", 0.6), ("nrho-3-1", 0.0)])
@pytest.mark.parametrize("target, t", TARGETS)
def test_cr3bp_radec_matches_independent_reference(orbit, phase, target, t):
    sensor = SpaceTelescope(orbit=orbit, phase=phase, moon_phase_deg=40.0)
    x_t = cr3bp_state(np.array(ORBITS[target].state), 0.0, t)
    ra, dec = sensor.measure(x_t[None], t)[0]
    o = ORBITS[orbit]
    ref = cr3bp_radec(x_t, np.array(o.state), -phase * o.period, t, np.radians(40.0))
    assert angle_between(ra, dec, *ref) < 1e-6 * ARCSEC_RAD


def test_cr3bp_geometric_radec_without_light_time_matches_reference():
    sensor = SpaceTelescope(orbit="dro-2-1", phase=0.5, light_time=False)
    x_t = cr3bp_state(np.array(ORBITS["nrho-9-2"].state), 0.0, 0.4)
    ra, dec = sensor.measure(x_t[None], 0.4)[0]
    o = ORBITS["dro-2-1"]
    ref = cr3bp_radec(x_t, np.array(o.state), -0.5 * o.period, 0.4, 0.0, light_time=False)
    assert angle_between(ra, dec, *ref) < 1e-6 * ARCSEC_RAD


def test_light_time_moves_the_direction_by_more_than_the_tolerance():
    """The comparison above is not blind to light time: switching it off moves the direction
    by far more than 1e-6 arcsec (an arcsecond or more)."""
    x_t = cr3bp_state(np.array(ORBITS["nrho-9-2"].state), 0.0, 0.3)
    on = SpaceTelescope(orbit="dro-2-1", phase=0.25).measure(x_t[None], 0.3)[0]
    off = SpaceTelescope(orbit="dro-2-1", phase=0.25, light_time=False).measure(x_t[None], 0.3)[0]
    assert angle_between(*on, *off) > 0.1 * ARCSEC_RAD


EPOCH = "2026-01-01T00:00:00Z"


@pytest.fixture(scope="module")
def ephemeris():
    from cistrack.plugins.dynamics.ephemeris import EphemerisDynamics
    return EphemerisDynamics(epoch=EPOCH)


@pytest.mark.parametrize("orbit, phase, target, t", [("dro-2-1", 0.25, "nrho-9-2", 0.3),
                                                      ("l2-lyapunov", 0.6, "nrho-9-2", 1.1),
                                                      ("dro-2-1", 0.0, "mirror-3-1", 0.9)])
def test_ephemeris_radec_matches_independent_reference(ephemeris, orbit, phase, target, t):
    from sensors.space_reference import ephemeris_radec
    sensor = SpaceTelescope(orbit=orbit, phase=phase, dynamics=ephemeris, epoch=EPOCH)
    x_t = np.asarray(ORBITS[target].state, dtype=float)     # any state near the Moon will do
    ra, dec = sensor.measure(x_t[None], t)[0]
    o = ORBITS[orbit]
    ref = ephemeris_radec(x_t, np.array(o.state), -phase * o.period, t, EPOCH)
    assert angle_between(ra, dec, *ref) < 0.01 * ARCSEC_RAD
