"""Multiple shooting carries CR3BP catalog orbits into the ephemeris model: the corrected patch
points form one continuous trajectory (checked by propagating it in one piece), it keeps the
catalog orbit's shape, and it stays bounded over ten revolutions (slow)."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import argrelmax, argrelmin

from cistrack import units
from cistrack.astro.ephemeris import DAY_S
from cistrack.plugins.dynamics.orbit_catalog import get_orbit
from cistrack.plugins.dynamics.ephemeris import EphemerisDynamics
from cistrack.plugins.dynamics.ephemeris_corrector import (
    catalog_patch_points, correct_catalog_orbit, correct_multiple_shooting)


@pytest.fixture(scope="module")
def dyn():
    return EphemerisDynamics(epoch="2026-01-01T00:00:00Z")


def _moon_distance_history(dyn, orbit, samples_per_rev: int = 2000):
    """Distance (km) from the Moon along ONE propagation from the first patch point."""
    revs = (len(orbit.times) - 1) / 8
    tt = np.linspace(orbit.times[0], orbit.times[-1], int(revs * samples_per_rev))
    p = dyn.propagate_inertial(orbit.states[0][None], orbit.times[0], tt[1:])
    km = units.state_to_km(p.states[:, 0])
    jd1, jd2 = dyn.frame.epoch_tdb
    moon, _ = dyn.frame.ephemeris.moon(jd1, jd2 + tt[1:] * units.TU_S / DAY_S)
    return bool(p.alive[0]), tt[1:], np.linalg.norm(km[:, :3] - moon, axis=1)


def test_corrected_patch_points_join_into_one_continuous_trajectory(dyn):
    orbit = get_orbit("nrho-9-2")
    guess = catalog_patch_points(dyn, np.asarray(orbit.state, float), orbit.period, 1)
    assert guess.jumps.max() > 1e-3  # the CR3BP guess is visibly discontinuous in this model
    fixed = correct_multiple_shooting(dyn, guess)
    assert fixed.jumps.max() < 1e-10
    # one propagation from the first patch point passes through every other one
    p = dyn.propagate_inertial(fixed.states[0][None], fixed.times[0], fixed.times[1:],
                               rtol=1e-13, atol=1e-13)
    miss_km = units.lu_to_km(np.linalg.norm(p.states[:, 0, :3] - fixed.states[1:, :3], axis=1))
    assert miss_km.max() < 1e-3


def test_corrected_nrho_keeps_the_catalog_shape(dyn):
    orbit = get_orbit("nrho-9-2")
    fixed = correct_multiple_shooting(
        dyn, catalog_patch_points(dyn, np.asarray(orbit.state, float), orbit.period, 1))
    alive, _, r = _moon_distance_history(dyn, fixed)
    assert alive
    assert 2500.0 < r.min() < 4500.0  # CR3BP perilune 3,260 km
    assert 60_000.0 < r.max() < 80_000.0  # CR3BP apolune ~71,000 km


@pytest.mark.slow
@pytest.mark.parametrize("name,perilune_km,apolune_km", [
    ("nrho-9-2", (2500.0, 4500.0), (65_000.0, 80_000.0)),
    ("dro-2-1", (50_000.0, 90_000.0), (60_000.0, 120_000.0)),
])
def test_catalog_orbit_stays_bounded_over_ten_revolutions(dyn, name, perilune_km, apolune_km):
    orbit = get_orbit(name)
    fixed = correct_catalog_orbit(dyn, np.asarray(orbit.state, float), orbit.period, 10)
    assert fixed.jumps.max() < 1e-10
    alive, tt, r = _moon_distance_history(dyn, fixed)
    assert alive
    lows, highs = r[argrelmin(r)[0]], r[argrelmax(r)[0]]
    assert len(lows) >= 9
    assert perilune_km[0] < lows.min() and lows.max() < perilune_km[1]
    assert apolune_km[0] < highs.min() and highs.max() < apolune_km[1]
