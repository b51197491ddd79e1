"""Where the burn search's full fits start (cistrack.least_squares.burn_search), on the three-site
NRHO campaign with a 0.3 m/s burn and one gross outlier (300 arcsec) that the ballistic fit
rejects: a gap's fit is made with those rejections out of its first pass as well as with every
observation in it, the cheaper kept; an unconverged one is fitted once more; the time check fits
the burn's own gap from the ballistic fit too."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from .burn_campaigns import burned, truth_state
from cistrack.least_squares import burn_search
from cistrack.least_squares.differential_correction import fit_orbit
from cistrack.least_squares.impulse_fit import BurnArc, capped_cost, fit_impulse, rejected_of
from cistrack.least_squares.options import FitOptions
from cistrack.model.measurement import MeasurementSet
from cistrack.units import ARCSEC_RAD

OPTS = FitOptions(area_to_mass="off")


@pytest.fixture(scope="module")
def case():
    """(burned campaign, its measurements with row 40 moved 300 arcsec, the ballistic fit, the arc,
    the gap that holds the burn)."""
    b = burned(0.3)
    ms = b.measurements
    values = ms.values.copy()
    values[40, 1] += 300.0 * ARCSEC_RAD
    ms = MeasurementSet(ms.times, values, ms.sigmas, ms.names, dict(ms.meta), ms.sites, ms.kinds, dict(ms.site_table))
    t0 = float(ms.times[-1])
    ballistic = fit_orbit(b.dynamics, b.sensor, ms, truth_state(b, t0), t0, options=OPTS)
    gap = next(w for w in burn_search._windows(ms.times, []) if w[0] <= b.t_burn <= w[1])
    return b, ms, ballistic, BurnArc(b.dynamics, b.sensor, ms, OPTS, None), gap


def test_the_ballistic_fit_rejects_the_outlier(case):
    _, _, ballistic, _, _ = case
    assert rejected_of(ballistic)[40]


def test_a_gap_fit_keeps_the_cheaper_of_its_two_starts(case):
    b, _, ballistic, arc, _ = case
    got = burn_search._gap_starts(arc, ballistic, np.array([b.t_burn]), [])
    starts = [fit_impulse(arc, ballistic.state, ballistic.epoch, [b.t_burn], rejected=r)
              for r in (None, rejected_of(ballistic))]
    assert capped_cost(got.fit) <= min(capped_cost(s.fit) for s in starts) + 1e-9


def test_a_gap_fit_measures_the_burn_within_three_sigma(case):
    b, _, ballistic, arc, _ = case
    est = burn_search._gap_starts(arc, ballistic, np.array([b.t_burn]), []).searched
    assert abs(est.magnitude_ms - np.linalg.norm(b.dv_ms)) <= 3 * est.magnitude_sigma_ms


def test_an_unconverged_gap_fit_is_fitted_once_more_and_converges_cheaper(case):
    b, ms, ballistic, arc, _ = case
    short = BurnArc(b.dynamics, b.sensor, ms, replace(OPTS, max_iterations=2, max_passes=1), None)
    stopped = fit_impulse(short, ballistic.state, ballistic.epoch, [b.t_burn])
    assert not stopped.fit.converged
    got = burn_search._continued(arc, stopped)
    assert got.fit.converged and capped_cost(got.fit) <= capped_cost(stopped.fit)


def test_a_converged_gap_fit_is_not_fitted_again(case):
    b, _, ballistic, arc, _ = case
    done = fit_impulse(arc, ballistic.state, ballistic.epoch, [b.t_burn], rejected=rejected_of(ballistic))
    assert done.fit.converged and burn_search._continued(arc, done) is done


def test_the_time_check_fits_the_burns_gap_from_the_ballistic_fit(case):
    """GAP_POINTS times across the gap, the burn's delta-v from zero: the cheapest of them is the
    one nearest the burn's true time."""
    b, _, ballistic, arc, gap = case
    fit = burn_search._gap_starts(arc, ballistic, np.array([b.t_burn]), [])
    found = burn_search.ManeuverSearch(fit.fit, burn_search.flown(b.dynamics, fit.burns), fit.burns, [gap],
                                       ballistic=ballistic)
    trials = burn_search._from_ballistic(arc, found, fit.burns[0], gap, capped_cost(fit.fit))
    assert len(trials) == burn_search.GAP_POINTS and all(gap[0] <= t[0] <= gap[1] for t in trials)
    best = min(trials, key=lambda t: t[1])[0]
    assert abs(best - b.t_burn) <= (gap[1] - gap[0]) / burn_search.GAP_POINTS


def test_a_search_without_its_ballistic_fit_has_no_such_trials(case):
    b, _, _, arc, gap = case
    found = burn_search.ManeuverSearch(None, b.dynamics, [], [gap])
    assert burn_search._from_ballistic(arc, found, None, gap, 0.0) == []
