"""The residual ladder: a fit of the latest arc carried back to an earlier one. Consistent when
one orbit is observed, broken after a velocity change between the arcs, lost when one night from
one site is carried back two months; the predicted spread on the sky is checked against orbits
drawn from the fit covariance and propagated one by one. (Where the cloud of orbits is curved
the unscented covariance is an approximation: carried back two months from one night of two
sites it gave 1.56 times the sampled spread at the earlier arc's last observation, the linear
covariance 0.52 times.)"""
from __future__ import annotations

import json
from dataclasses import replace
from functools import lru_cache

import numpy as np
import pytest

from cistrack.fitting.arcs import ArcSpan, long_gap_arcs, observation_groups
from cistrack.fitting.residual_ladder import fitted_dynamics, ladder_json, ladder_rung, ladder_table, residual_ladder
from cistrack.least_squares import fit_orbit
from cistrack.units import ARCSEC_RAD, hours_to_tu

from .arc_campaigns import two_arcs


def _fit(c, sub):
    return fit_orbit(c.dynamics, c.sensor, sub, c.truth_at(sub.times[-1:])[0], sub.times[-1])


@lru_cache(maxsize=1)
def _dro_two_months():
    """The DRO's two arcs 60 days apart, and the fit of the later arc."""
    c = two_arcs(60.0)
    arcs = long_gap_arcs(c.measurements.times)
    return c, arcs, _fit(c, c.measurements.subset(arcs[-1].rows))


def test_one_orbit_two_months_apart_is_consistent_and_printable():
    c, arcs, fit = _dro_two_months()
    ms = c.measurements
    rungs = residual_ladder(fit, c.dynamics, c.sensor, ms, arcs[:-1])
    assert [r.verdict for r in rungs] == ["consistent"]
    r = rungs[0]
    assert r.n == arcs[0].n and set(r.sites) == {"711", "809"}
    assert 0 < r.rms_arcsec <= r.max_arcsec and r.sigmas <= r.max_sigmas < 5
    text = ladder_table(rungs, c.epoch)
    assert max(len(line) for line in text.splitlines()) <= 120 and "consistent" in text
    record = json.loads(json.dumps(ladder_json(rungs, c.epoch)))
    assert record[0]["first_utc"].startswith("2026-03-0") and record[0]["verdict"] == "consistent"


def test_a_velocity_change_between_the_arcs_is_a_broken_link():
    c = two_arcs(6.0, dv_mps=5.0)
    ms = c.measurements
    groups = observation_groups(ms.times)
    rung = ladder_rung(_fit(c, ms.subset(groups[-1].rows)), c.dynamics, c.sensor, ms, groups[0])
    assert rung.verdict == "broken"
    assert rung.sigmas > 5 and rung.rms_arcsec > 100


def test_one_night_from_one_site_carried_back_two_months_is_lost():
    c = two_arcs(60.0)
    ms = c.measurements
    arcs = long_gap_arcs(ms.times)
    last = ms.subset(arcs[-1].rows)
    night = last.subset((last.times <= last.times[0] + hours_to_tu(12.0)) & (last.sites == "711"))
    rung = ladder_rung(_fit(c, night), c.dynamics, c.sensor, ms, arcs[0])
    assert rung.verdict == "prediction lost" and "degrees on the sky" in rung.why
    assert "prediction lost" in ladder_table([rung], c.epoch)
    assert json.loads(json.dumps(ladder_json([rung], c.epoch)))[0]["verdict"] == "prediction lost"


@pytest.mark.slow
def test_the_predicted_sky_spread_matches_orbits_drawn_from_the_fit():
    """Predicted 1-sigma on the sky (largest axis) at three times of the earlier arc against the
    spread of 600 orbits drawn from the fit covariance (seeded), each propagated by the dynamics
    and measured by the sensor: within 12 % (the sample's own error is about 3 %)."""
    c, arcs, fit = _dro_two_months()
    ms = c.measurements
    rng = np.random.default_rng(4901)
    draws = rng.multivariate_normal(fit.state, fit.covariance, size=600)
    for i in arcs[0].rows[[0, arcs[0].n // 2, -1]]:
        t = float(ms.times[i])
        rung = ladder_rung(fit, c.dynamics, c.sensor, ms, ArcSpan(np.array([i]), t, t, 60.0))
        states = c.dynamics.propagate(draws, fit.epoch, np.array([t])).states[0]
        z = np.asarray(c.sensor.measure(states, np.full(len(states), t)))[:, :2]
        dz = (z - np.mean(z, axis=0) + np.pi) % (2 * np.pi) - np.pi
        dz[:, 0] *= np.cos(np.mean(z[:, 1]))
        sample = np.sqrt(np.linalg.eigvalsh(np.cov(dz.T))[-1]) / ARCSEC_RAD
        assert rung.sky_sigma_arcsec == pytest.approx(sample, rel=0.12)


@pytest.mark.slow
def test_links_hold_for_one_orbit_and_break_after_two_metres_per_second():
    """Eight campaigns (seeds 30-37) of two 4-day DRO arcs 6 days apart: with one orbit every
    link holds (median miss 0.55-3.15 sigma against the 3.9 bound), after a 2 m/s velocity change
    in the gap every link breaks (3.95-7.06 sigma); at 1 m/s one of the eight broke."""
    for dv, verdict in ((0.0, "consistent"), (2.0, "broken")):
        for seed in range(30, 38):
            c = two_arcs(6.0, dv, seed)
            ms = c.measurements
            groups = observation_groups(ms.times)
            rung = ladder_rung(_fit(c, ms.subset(groups[-1].rows)), c.dynamics, c.sensor, ms, groups[0])
            assert rung.verdict == verdict, (dv, seed, rung.sigmas)


def test_the_ladder_predicts_with_the_fits_solve_for_parameters():
    c, _arcs, fit = _dro_two_months()
    assert fitted_dynamics(c.dynamics, fit) is c.dynamics
    with_amr = replace(fit, parameter_names=("area_to_mass_m2_kg",), parameters=np.array([0.02]))
    assert fitted_dynamics(c.dynamics, with_amr).parameter("area_to_mass_m2_kg") == pytest.approx(0.02)
