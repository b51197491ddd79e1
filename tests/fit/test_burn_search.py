"""The burn search of cistrack.least_squares.burn_search on an arc with an impulsive burn between
nights: found in the right gap, its delta-v within 3 sigma, nothing found without a burn."""
from __future__ import annotations

import numpy as np
import pytest

from .burn_campaigns import burned, truth_state
from cistrack.least_squares.burn_search import search_maneuvers, suspicion
from cistrack.least_squares.differential_correction import fit_orbit
from cistrack.least_squares.options import FitOptions

OPTS = FitOptions(area_to_mass="off")


def _ballistic(b):
    t0 = float(b.measurements.times[-1])
    return fit_orbit(b.dynamics, b.sensor, b.measurements, truth_state(b, t0), t0, options=OPTS)


@pytest.fixture(scope="module")
def burn_03():
    b = burned(0.3)
    ballistic = _ballistic(b)
    return b, ballistic, search_maneuvers(b.dynamics, b.sensor, b.measurements, ballistic, OPTS)


def test_a_burn_between_nights_makes_the_ballistic_fit_suspect(burn_03):
    _, ballistic, _ = burn_03
    assert "contiguous block" in suspicion(ballistic)


def test_the_search_keeps_one_burn_in_or_next_to_the_gap_that_holds_it(burn_03):
    """The burn is 14 minutes after the last observation before a night's gap: the gap before that
    observation explains the data almost as well, so the gap kept may be either (its time's sigma
    reaches the truth)."""
    b, _, found = burn_03
    assert len(found.burns) == 1
    lo, hi = found.windows[0]
    s = found.burns[0].t_sigma
    assert lo - 3 * s < b.t_burn < hi + 3 * s


def test_the_burn_time_is_within_three_sigma(burn_03):
    b, _, found = burn_03
    est = found.burns[0]
    assert abs(est.t - b.t_burn) <= 3 * est.t_sigma


def test_the_delta_v_is_within_three_sigma_of_the_truth(burn_03):
    b, _, found = burn_03
    est = found.burns[0]
    assert abs(est.magnitude_ms - np.linalg.norm(b.dv_ms)) <= 3 * est.magnitude_sigma_ms
    assert est.magnitude_sigma_ms < 0.5 * np.linalg.norm(b.dv_ms)  # and the data determine it


def test_the_fit_with_the_burn_uses_every_observation(burn_03):
    _, _, found = burn_03
    assert found.result.converged and found.result.n_rejected <= 2
    assert 0.8 < found.result.rms < 1.2


def test_the_state_after_the_burn_lies_inside_the_covariance(burn_03):
    b, _, found = burn_03
    r = found.result
    e = r.state - truth_state(b, float(r.epoch))
    assert e @ np.linalg.solve(r.covariance, e) <= 22.5


@pytest.mark.slow
def test_no_burn_is_kept_for_an_object_that_did_not_maneuver():
    b = burned(0.0)
    ballistic = _ballistic(b)
    assert suspicion(ballistic) == ""
    found = search_maneuvers(b.dynamics, b.sensor, b.measurements, ballistic, OPTS)
    assert found.burns == []


@pytest.fixture(scope="module")
def clean_fit():
    return _ballistic(burned(0.0))


def _with_rejected(fit, rows):
    from dataclasses import replace

    rejected = np.zeros(len(fit.residuals.rejected), dtype=bool)
    order = np.argsort(fit.residuals.times, kind="stable")
    rejected[order[rows]] = True
    return replace(fit, residuals=replace(fit.residuals, rejected=rejected))


def test_a_block_of_rejections_that_ends_the_arc_makes_the_fit_suspect(clean_fit):
    n = len(clean_fit.residuals.rejected)
    assert "contiguous block" in suspicion(_with_rejected(clean_fit, np.arange(n - 10, n)))


def test_a_block_of_rejections_between_accepted_observations_is_bad_data_not_a_maneuver(clean_fit):
    """One mis-identified tracklet in the middle of the arc: after a burn every later observation
    would be off the ballistic orbit, so a block with accepted observations after it is no burn's."""
    n = len(clean_fit.residuals.rejected)
    assert suspicion(_with_rejected(clean_fit, np.arange(n // 2, n // 2 + 10))) == ""


@pytest.mark.parametrize("cost, sigmas_away", [(1.0, 2.0), (4.0, 2.0), (6.25, 2.5), (9.0, 3.0)])
def test_an_allowed_time_whose_fit_costs_c_more_lies_max_2_sqrt_c_sigmas_away(cost, sigmas_away):
    """The time's profile: a time costing 9 more is three sigmas away, one costing 4 or less two
    (the widening before times costing 4-9 more were allowed)."""
    from cistrack.least_squares.burn_search import _widened
    from cistrack.least_squares.impulse_fit import BurnEstimate

    b = BurnEstimate(1.0, np.array([0.5, 0.0, 0.0]), np.eye(3) * 1e-4, 0.01)
    m = max(2.0, np.sqrt(cost))
    w = _widened(b, [(1.3, np.array([0.8, 0.0, 0.0]), m)])
    assert m == pytest.approx(sigmas_away)
    assert w.t_sigma == pytest.approx(0.3 / sigmas_away) and w.widened
    assert w.covariance_ms2[0, 0] == pytest.approx(1e-4 + (0.3 / sigmas_away) ** 2)
