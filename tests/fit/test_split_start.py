"""Burn fits started where the orbits of a gap's two sides meet
(cistrack.least_squares.split_start), on the three-site NRHO campaign with a 0.3 m/s burn at
3.4 days (burn_campaigns.burned)."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from .burn_campaigns import burned, truth_state
from cistrack import units
from cistrack.least_squares.burn_search import _windows
from cistrack.least_squares.differential_correction import fit_orbit
from cistrack.least_squares.impulse_fit import BurnArc, burn_time_profile, with_time_uncertainty
from cistrack.least_squares.options import FitOptions
from cistrack.least_squares.split_start import side_nights, split_candidates, split_fit

OPTS = FitOptions(area_to_mass="off")


@pytest.fixture(scope="module")
def campaign():
    b = burned(0.3)
    t0 = float(b.measurements.times[-1])
    ballistic = fit_orbit(b.dynamics, b.sensor, b.measurements, truth_state(b, t0), t0, options=OPTS)
    arc = BurnArc(b.dynamics, b.sensor, b.measurements, OPTS)
    splits = split_candidates(arc, ballistic, b.dynamics, _windows(b.measurements.times, []))
    return b, ballistic, arc, splits


def test_observations_hours_apart_are_one_night_and_a_day_apart_two():
    hours = units.hours_to_tu(1.0)
    assert side_nights(np.array([0.0, hours, 2 * hours])) == 1
    assert side_nights(np.array([0.0, hours, 24 * hours])) == 2
    assert side_nights(np.array([])) == 0


def test_the_orbits_either_side_of_the_burns_gap_meet_closest_of_all_gaps(campaign):
    b, _, _, splits = campaign
    lo, hi = splits[0].gap
    assert lo < b.t_burn < hi
    assert units.lu_to_km(splits[0].starts[0][2]) < 0.5 * units.lu_to_km(splits[1].starts[0][2])


def test_a_gap_with_one_night_on_a_side_is_not_split(campaign):
    b, _, _, splits = campaign
    first_night_end = float(b.measurements.times[b.measurements.times < units.days_to_tu(0.7)].max())
    assert all(s.gap[0] > first_night_end for s in splits)


def test_the_fit_from_the_meeting_point_measures_the_burn_within_three_sigma(campaign):
    b, ballistic, arc, splits = campaign
    fit = split_fit(arc, ballistic, b.dynamics, splits[0], [])
    _, t_sigma = burn_time_profile(arc, replace(ballistic, state=fit.fit.state), *splits[0].gap)
    est = with_time_uncertainty(arc, fit, t_sigma, bounds=splits[0].gap).searched
    e = est.delta_v_ms - b.dv_ms
    assert abs(est.t - b.t_burn) <= 3.0 * est.t_sigma
    assert e @ np.linalg.solve(est.covariance_ms2, e) <= 14.2  # 3 dof at 99.7 %
    assert fit.fit.converged and fit.fit.n_rejected <= 2
