"""The orbit catalog and the differential corrector that produced it."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack import units
from cistrack.interfaces import ReferenceOrbit
from cistrack.plugins.dynamics.orbit_catalog import GUESSES, ORBITS
from cistrack.plugins.dynamics.corrector import (CorrectionError, correct_symmetric_orbit,
                                                 propagate_with_stm)
from cistrack.plugins.dynamics.cr3bp import CR3BP

NAMES = ["nrho-9-2", "nrho-3-1", "l2-lyapunov", "dro-2-1", "mirror-3-1", "l2-transit"]


def test_every_catalog_orbit_is_registered_by_name(registry):
    assert set(NAMES) <= set(registry.names("orbit"))
    for name in NAMES:
        orbit = registry.create("orbit", name)
        assert isinstance(orbit, ReferenceOrbit) and orbit.name == name
        assert orbit.state.shape == (6,) and orbit.mu == pytest.approx(1.2150582e-2)
        assert orbit.description


def test_slow_transit_is_not_periodic():
    assert ORBITS["l2-transit"].period is None


@pytest.mark.parametrize("name", sorted(GUESSES))
def test_recorrecting_the_published_guess_reproduces_the_catalog_state(name):
    guess, period = GUESSES[name]
    orb = correct_symmetric_orbit(guess, fixed="x", period_guess=period)
    np.testing.assert_allclose(orb.state, ORBITS[name].state, rtol=0, atol=1e-10)
    assert orb.period == pytest.approx(ORBITS[name].period, abs=1e-9)


def test_nrho_9_2_period_and_perilune_agree_with_the_reference():
    orbit = ORBITS["nrho-9-2"]
    assert units.tu_to_days(orbit.period) == pytest.approx(6.56, abs=0.02)
    prop = CR3BP().propagate(orbit.state, 0.0, np.linspace(0, orbit.period, 4001)[1:])
    moon = np.array([1 - orbit.mu, 0, 0])
    perilune_km = np.min(np.linalg.norm(prop.states[:, 0, :3] - moon, axis=1)) * units.LU_KM
    assert perilune_km == pytest.approx(3250.0, abs=60.0)


def test_mirror_orbit_is_planar_with_perigee_near_50700_km():
    orbit = ORBITS["mirror-3-1"]
    assert orbit.state[2] == 0 and orbit.state[5] == 0
    earth = np.array([-orbit.mu, 0, 0])
    assert np.linalg.norm(orbit.state[:3] - earth) * units.LU_KM == pytest.approx(50700.0, abs=100.0)
    assert units.tu_to_days(orbit.period) == pytest.approx(27.2, abs=0.1)


def test_mirror_orbit_is_symmetric_about_the_x_axis():
    orbit = ORBITS["mirror-3-1"]
    t = 0.37 * orbit.period
    dyn = CR3BP(rtol=1e-13, atol=1e-14)
    fwd = dyn.propagate(orbit.state, 0.0, t).final[0]
    bwd = dyn.propagate(orbit.state, 0.0, -t).final[0]
    # (x, y, vx, vy)(t) = (x, -y, -vx, vy)(-t)
    np.testing.assert_allclose(fwd[[0, 1, 3, 4]], bwd[[0, 1, 3, 4]] * [1, -1, -1, 1], atol=1e-9)


def test_stm_matches_finite_differences():
    x0 = ORBITS["dro-2-1"].state
    _, phi = propagate_with_stm(x0, 0.5)
    eps = 1e-6
    fd = np.empty((6, 6))
    for j in range(6):
        dp, dm = x0.copy(), x0.copy()
        dp[j] += eps
        dm[j] -= eps
        fd[:, j] = (propagate_with_stm(dp, 0.5)[0] - propagate_with_stm(dm, 0.5)[0]) / (2 * eps)
    np.testing.assert_allclose(phi, fd, rtol=1e-6, atol=1e-6)


def test_corrector_can_hold_z0_fixed():
    guess, period = GUESSES["nrho-9-2"]
    ref = ORBITS["nrho-9-2"].state
    orb = correct_symmetric_orbit(ref + [1e-5, 0, 0, 0, 1e-5, 0], fixed="z", period_guess=period)
    assert orb.state[2] == ref[2]
    assert orb.residual <= 1e-12


def test_corrector_reports_non_convergence_clearly():
    with pytest.raises(CorrectionError, match="did not converge|does not cross"):
        correct_symmetric_orbit([1.3, 0, 0, 0, 0.9, 0], fixed="x", max_iter=2)


def test_corrector_rejects_z_fixed_for_planar_guess():
    with pytest.raises(CorrectionError, match="planar"):
        correct_symmetric_orbit([1.1257, 0, 0, 0, 0.1508, 0], fixed="z")
