"""The area-to-mass solve-for recovers a simulated ratio: arcs of weeks of RA/Dec (``real-telescope``,
1 arcsec) from two observatories (MPC 711 McDonald, 809 La Silla), a few observations per site
and night, of a distant retrograde orbit integrated with a known C_R A/m; the fit starts 50 km and 0.5 m/s off
with A/m = 0 and must put the truth within 3 sigma (the covariance scaled by the noise scale
when that exceeds 1). The short checks: with the option off the fit is the 6-parameter one bit
for bit; "auto" declines a short arc and keeps a clear detection."""
from __future__ import annotations

from functools import lru_cache

import numpy as np
import pytest

from cistrack.astro.site_network import SiteNetwork, merge_sites
from cistrack.astro.sites import observatory
from cistrack.least_squares import FitOptions, fit_orbit
from cistrack.model.measurement import MeasurementSet
from cistrack.plugin.registry import default_registry
from cistrack.units import LU_KM, TU_S, hours_to_tu, km_to_lu, kms_to_vu

EPOCH = "2026-01-01T00:00:00Z"
DRO = np.array([0.7957, 0.0, 0.0, 0.0, 0.53181952, 0.0])
"""The 2:1 distant retrograde orbit (CR3BP catalog); placed in the ephemeris model it stays
within 63,000-134,000 km of the Moon for six weeks from :data:`EPOCH`."""
OFFSET = np.concatenate([np.full(3, km_to_lu(50.0)), np.full(3, kms_to_vu(5e-4))])
SITES = ("711", "809")


def _per_night(times: np.ndarray, seen: np.ndarray, per_night: int, rng: np.random.Generator) -> np.ndarray:
    """Indices of ``per_night`` consecutive visible grid points (40 min apart) in each visible
    stretch (night) of ``seen`` (K,) bool, started at a random point of the stretch."""
    idx = np.flatnonzero(seen)
    if idx.size == 0:
        return idx
    breaks = np.flatnonzero(np.diff(idx) > 1) + 1
    keep = []
    for night in np.split(idx, breaks):
        first = int(rng.integers(0, max(1, night.size - per_night + 1)))
        keep.extend(night[first:first + per_night])
    return np.array(keep, dtype=int)


def simulate(area_to_mass: float, days: float, seed: int, per_night: int = 4, sigma_arcsec: float = 1.0):
    """(fit dynamics with A/m = 0, site network, measurements, truth (6,) at t = 0) of the 2:1
    DRO placed in the ephemeris model at :data:`EPOCH`, integrated with C_R A/m =
    ``area_to_mass`` m^2/kg, observed over ``days`` from :data:`SITES`; noise from
    ``np.random.default_rng(seed)``."""
    reg = default_registry()
    fit_dyn = reg.create("dynamics", "ephemeris", epoch=EPOCH)
    truth_dyn = reg.create("dynamics", "ephemeris", epoch=EPOCH, area_to_mass_m2_kg=area_to_mass)
    x0 = fit_dyn.frame.gcrs_to_synodic(fit_dyn.frame.pulsating_to_gcrs(DRO, 0.0), 0.0)
    grid = np.arange(1, int(days * 36) + 1) * float(hours_to_tu(40.0 / 60.0))
    truth = truth_dyn.propagate(x0[None], 0.0, grid).states[:, 0]
    rng = np.random.default_rng(seed)
    parts, members = [], {}
    for code in SITES:
        site = observatory(code)
        sen = reg.create("sensor", "real-telescope", epoch=EPOCH, measurement="radec", sigma_arcsec=sigma_arcsec,
                         latitude_deg=site.latitude_deg, longitude_deg=site.longitude_deg, height_m=site.height_m)
        k = _per_night(grid, sen.visible(truth, grid), per_night, rng)
        z = sen.measure(truth[k], grid[k])
        sig = sen.sigmas(truth[k], grid[k])
        z = z + rng.standard_normal(z.shape) * sig
        parts.append((code, site, MeasurementSet(grid[k], z, sig, sen.names)))
        members[code] = sen
    ms = merge_sites(parts)
    return fit_dyn, SiteNetwork(members, ms.times, ms.sites), ms, x0


@lru_cache(maxsize=8)
def recovered(area_to_mass: float, days: float, seed: int, mode: str = "solve"):
    """The fit of :func:`simulate`'s arc from a start 50 km and 0.5 m/s off, A/m from 0."""
    dyn, sensor, ms, x0 = simulate(area_to_mass, days, seed)
    return fit_orbit(dyn, sensor, ms, x0 + OFFSET, 0.0, options=FitOptions(area_to_mass=mode)), x0


def _z(res, truth: float) -> float:
    value, sigma = res.parameter("area_to_mass_m2_kg")
    return (value - truth) / (sigma * max(1.0, res.noise_scale))


def test_off_is_the_six_parameter_fit_bit_for_bit():
    dyn, sensor, ms, x0 = simulate(0.0, 3.0, seed=3)
    plain = fit_orbit(dyn, sensor, ms, x0 + OFFSET, 0.0)
    off = fit_orbit(dyn, sensor, ms, x0 + OFFSET, 0.0, options=FitOptions(area_to_mass="off"))
    np.testing.assert_array_equal(plain.state, off.state)
    np.testing.assert_array_equal(plain.covariance, off.covariance)
    assert off.parameter_names == () and off.full_covariance is None and plain.chi2 == off.chi2


def test_auto_declines_a_short_arc_and_returns_the_six_parameter_orbit():
    dyn, sensor, ms, x0 = simulate(0.01, 3.0, seed=3)
    plain = fit_orbit(dyn, sensor, ms, x0 + OFFSET, 0.0)
    auto = fit_orbit(dyn, sensor, ms, x0 + OFFSET, 0.0, options=FitOptions(area_to_mass="auto"))
    np.testing.assert_array_equal(plain.state, auto.state)
    assert auto.parameter_names == ()
    assert "not estimated: the arc spans" in auto.area_to_mass_decision


def test_a_bad_mode_is_refused_naming_the_option():
    from cistrack.errors import ParameterError

    with pytest.raises(ParameterError, match="area_to_mass"):
        FitOptions(area_to_mass="yes")


@pytest.mark.slow
@pytest.mark.parametrize("area_to_mass,seed", [(0.01, 101), (0.002, 202)])
def test_a_four_week_arc_recovers_the_ratio_within_3_sigma(area_to_mass, seed):
    res, x0 = recovered(area_to_mass, 28.0, seed)
    assert res.converged
    assert abs(_z(res, area_to_mass)) < 3.0, (res.parameter("area_to_mass_m2_kg"), res.noise_scale)
    e = res.state - x0
    assert np.linalg.norm(e[:3]) * LU_KM < 3.0 * np.linalg.norm(res.sigmas_km[:3]) + 1.0


@pytest.mark.slow
def test_auto_estimates_a_clear_ratio_on_a_four_week_arc():
    res, _ = recovered(0.01, 28.0, 101, mode="auto")
    assert res.parameter_names == ("area_to_mass_m2_kg",), res.area_to_mass_decision
    assert res.area_to_mass_decision.startswith("estimated")
    assert TU_S > 0
