"""The burn search of cistrack.least_squares.burn_search on an arc with an impulsive burn between
nights: found in the right gap, its delta-v within 3 sigma, nothing found without a burn."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from .burn_campaigns import burned, truth_state
from cistrack.least_squares.burn_search import burn_key, screen_suspicion, search_maneuvers, suspicion
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


def test_each_screened_step_is_kept_under_the_burns_found_before_it(burn_03):
    """The first step screens with no burn found; the second, which kept none, with the one burn."""
    _, _, found = burn_03
    assert set(found.screened) == {(), burn_key(found.burns)}


def test_a_search_made_again_reuses_the_first_ones_screened_steps(burn_03):
    """Searching again adds fits from where a gap's sides meet; the screened steps of the burns
    the first search found are not made again."""
    b, ballistic, found = burn_03
    steps = dict(found.screened)
    again = search_maneuvers(b.dynamics, b.sensor, b.measurements, ballistic, OPTS, again=replace(found))
    assert all(again.screened[k] is v for k, v in steps.items())
    assert len(again.burns) == 1 and abs(again.burns[0].t - b.t_burn) <= 3 * again.burns[0].t_sigma


def test_the_burn_key_tells_burns_apart_by_time_and_by_delta_v(burn_03):
    _, _, found = burn_03
    b = found.burns[0]
    assert burn_key([b]) == burn_key([replace(b)])
    assert burn_key([b]) != burn_key([replace(b, t=b.t + 1e-9)])
    assert burn_key([b]) != burn_key([replace(b, delta_v_ms=np.asarray(b.delta_v_ms) * (1 + 1e-12))])


def test_the_screen_passes_the_ballistic_fit_of_an_object_that_did_not_maneuver():
    b = burned(0.0)
    ballistic = _ballistic(b)
    assert screen_suspicion(b.dynamics, b.sensor, b.measurements, ballistic, OPTS) == ""


def test_the_screen_names_a_gap_where_a_burn_the_ballistic_fit_absorbed_lowers_its_cost():
    """1 cm/s: the ballistic fit passes every symptom (weighted RMS 1.01), yet a burn in a gap lowers
    its cost by more than a burn's test needs (chi-square 23.5, 4 dof at 1e-4)."""
    b = burned(0.01)
    ballistic = _ballistic(b)
    assert suspicion(ballistic) == ""
    why = screen_suspicion(b.dynamics, b.sensor, b.measurements, ballistic, OPTS)
    drop = float(why.split("lowers its cost by ")[1].split()[0])
    assert drop > 23.5, why


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


def _placed_a_night_early(b):
    """A search's burn put (fitted in full) in the night's gap before the one holding the burn."""
    from cistrack import units
    from cistrack.least_squares.burn_search import ManeuverSearch, _windows, burn_fit_options, flown
    from cistrack.least_squares.impulse_fit import BurnArc, fit_impulses

    arc = BurnArc(b.dynamics, b.sensor, b.measurements, burn_fit_options(OPTS))
    nights = [w for w in _windows(b.measurements.times, []) if w[1] - w[0] > units.hours_to_tu(3.0)]
    k = next(i for i, (lo, hi) in enumerate(nights) if lo <= b.t_burn <= hi)
    t0, gap = float(b.measurements.times[-1]), nights[k - 1]
    one = fit_impulses(arc, truth_state(b, t0), t0, [0.5 * (gap[0] + gap[1])])
    burn = replace(one.burns[0], t_sigma=float(units.hours_to_tu(1.0)))
    return arc, ManeuverSearch(one.fit, flown(b.dynamics, [burn]), [burn], [gap], [], None)


def test_a_burn_the_time_check_finds_clearly_better_elsewhere_is_moved_there_and_checked_again(burn_03):
    """The time check's trial fit in the true night's gap costs 210 less than the misplaced burn's:
    the burn is moved there, refitted and its time measured, and no time beats it again."""
    from cistrack.least_squares.burn_search import times_allowed

    b = burn_03[0]
    arc, found = _placed_a_night_early(b)
    out, why = times_allowed(arc, found)
    assert why == ""
    est = out.burns[0]
    assert abs(est.t - b.t_burn) <= 3 * est.t_sigma
    assert abs(est.magnitude_ms - np.linalg.norm(b.dv_ms)) <= 3 * est.magnitude_sigma_ms
    assert any(n.startswith("the time check moved burn 1") for n in out.notes)


def test_a_moved_burn_that_a_trial_time_beats_again_leaves_the_time_undetermined(burn_03, monkeypatch):
    """With every trial time counted as clearly better (the rival margin set below any cost), the
    second check beats the moved burn too: the search comes back as it was, its time not determined."""
    from cistrack.least_squares import burn_search

    arc, found = _placed_a_night_early(burn_03[0])
    monkeypatch.setattr(burn_search, "RIVAL_COST", -1e12)
    out, why = burn_search.times_allowed(arc, found)
    assert "; moved there, " in why and "than the moved one" in why and why.endswith("the burn's time is not determined")
    assert out is found


def _burn_arc(b):
    from cistrack.least_squares.burn_search import burn_fit_options
    from cistrack.least_squares.impulse_fit import BurnArc

    return BurnArc(b.dynamics, b.sensor, b.measurements, burn_fit_options(OPTS))


def test_the_observations_either_side_of_the_found_burn_each_determine_an_orbit(burn_03):
    from cistrack.least_squares.burn_search import _sides_undetermined

    b, _, found = burn_03
    assert _sides_undetermined(_burn_arc(b), found, found.burns[0].t) == ""


def test_a_burn_time_after_the_first_few_exposures_leaves_the_side_before_it_undetermined(burn_03):
    """Four exposures over minutes do not determine an orbit alone: a burn moved after them could
    trade its size against the orbit before it, and is not moved there."""
    from cistrack.least_squares.burn_search import _sides_undetermined

    b, _, found = burn_03
    t = np.asarray(b.measurements.times, dtype=float)
    why = _sides_undetermined(_burn_arc(b), found, 0.5 * (t[3] + t[4]))
    assert why.startswith("the 4 observations before it")


def test_the_time_check_walks_out_from_the_burn_time_doubling_until_the_cost_exceeds_the_allowed(burn_03):
    """Trial times max(4 time sigmas, 5 minutes) either side of the burn and each next twice as far,
    each side stopping at the first fit costing more than ALLOWED_COST or at the gap's edge."""
    from cistrack.least_squares.burn_search import ALLOWED_COST, WALK_STEPS, _walked
    from cistrack.least_squares.impulse_fit import capped_cost

    b, _, found = burn_03
    arc, est = _burn_arc(b), found.burns[0]
    walked = _walked(arc, found, est, found.windows[0], capped_cost(found.result, arc.prior))
    for side, edge in ((-1.0, found.windows[0][0]), (1.0, found.windows[0][1])):
        mine = [w for w in walked if np.sign(w[0] - est.t) == side]
        assert len(mine) <= WALK_STEPS and (mine or est.t == edge)
        assert all(c <= ALLOWED_COST for _, c, _ in mine[:-1])
        assert not mine or mine[-1][1] > ALLOWED_COST or mine[-1][0] == edge or len(mine) == WALK_STEPS
        gaps = np.abs([t - est.t for t, _, _ in mine])
        assert np.allclose(gaps[1:] / gaps[:-1], 2.0) or mine[-1][0] == edge
