"""A burn estimate is reported confirmed only when it is consistent (cistrack.runs.maneuver_watch._doubt),
and a burn time's uncertainty is never a silent 0 (cistrack.least_squares.impulse_fit): a burn found
first keeps its time uncertainty when refitted jointly with a later one; an interval too short for the
time's profile is an error, not a burn with t_sigma 0."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from cistrack.least_squares.errors import FitError
from cistrack.least_squares.impulse_fit import BurnEstimate, ImpulseFit, with_time_uncertainty
from cistrack.runs.maneuver_watch import _doubt, _Estimate, _record
from cistrack.interfaces.maneuvers import Detection


def _burn(t=1.0, dv=(1.0, 0.0, 0.0), t_sigma=0.01, g=(2.0, 0.0, 0.0)):
    return BurnEstimate(t, np.array(dv), np.eye(3) * 0.01, t_sigma, None if g is None else np.array(g))


def _found(burns, windows, chi2_each=2.0, n=20, rejected=0, prior=None):
    chi2 = np.full(n, chi2_each)
    chi2[:rejected] = 1e4
    res = SimpleNamespace(chi2=chi2, normalised=np.ones((n, 2)), rejected=np.arange(n) < rejected)
    fit = SimpleNamespace(residuals=res, rejection_threshold=9.0, parameter_names=(), state=np.zeros(6))
    return SimpleNamespace(burns=burns, windows=windows, result=fit, prior=prior, notes=[])


def test_a_joint_refit_keeps_the_earlier_burns_time_uncertainty():
    first = _burn(t_sigma=0.05, g=(2.0, 0.0, 0.0))
    refit = BurnEstimate(first.t, np.array([1.1, 0.0, 0.0]), np.eye(3) * 0.01)  # time held: t_sigma 0
    kept = first.refitted(refit)
    assert kept.t_sigma == 0.05
    assert kept.covariance_ms2[0, 0] == pytest.approx(0.01 + 4.0 * 0.05 ** 2)
    np.testing.assert_array_equal(kept.delta_v_ms, refit.delta_v_ms)


def test_an_interval_too_short_for_the_time_profile_is_an_error_not_a_zero_sigma():
    fit = ImpulseFit([_burn(t=1.0, t_sigma=0.0, g=None)], fit=None)
    with pytest.raises(FitError, match="cannot be measured"):
        with_time_uncertainty(None, fit, 0.01, bounds=(0.999, 1.001))


def test_a_consistent_single_burn_is_confirmed():
    b = _burn()
    assert _doubt(_found([b], [(0.5, 1.5)]), [b], 2.0) == ""


def test_a_burn_without_a_measured_time_uncertainty_is_unconfirmed():
    b = _burn(t_sigma=0.0, g=None)
    assert "uncertainty could not be measured" in _doubt(_found([b], [(0.5, 1.5)]), [b], 2.0)


def test_a_burn_outside_its_gap_or_after_the_detection_is_unconfirmed():
    b = _burn(t=1.0)
    assert "outside the gap" in _doubt(_found([b], [(1.2, 1.5)]), [b], 2.0)
    assert "after the detection" in _doubt(_found([b], [(0.5, 1.5)]), [b], 0.9)


def test_a_change_split_over_two_burns_before_the_detection_is_unconfirmed():
    a, b = _burn(t=0.8), _burn(t=1.0)
    assert "split the change over 2 burns" in _doubt(_found([a, b], [(0.7, 0.9), (0.95, 1.5)]), [a, b], 2.0)


def test_a_fit_whose_residuals_exceed_the_chi_square_bound_is_unconfirmed():
    """40 components (20 observations of 2), no prior: 34 dof, bound about 70 at 1e-4; 8 of 20
    rejected (capped at 9 each) and the rest at 2 each give 96."""
    b = _burn()
    assert _doubt(_found([b], [(0.5, 1.5)], rejected=8), [b], 2.0).startswith("the fit with the burn does not fit")
    assert _doubt(_found([b], [(0.5, 1.5)], rejected=1), [b], 2.0) == ""


def _ballistic(chi2_each, offset, n=20):
    """A ballistic fit of ``n`` observations at ``chi2_each`` each, its state ``offset`` (6,) from the
    prior's mean (zero, identity covariance: the prior's term is |offset|^2)."""
    res = SimpleNamespace(chi2=np.full(n, chi2_each), normalised=np.ones((n, 2)), rejected=np.zeros(n, dtype=bool))
    return SimpleNamespace(residuals=res, rejection_threshold=9.0, parameter_names=(), state=np.asarray(offset, float),
                           epoch=0.5)


PRIOR = (np.zeros(6), np.eye(6))


def test_a_burn_whose_evidence_is_the_priors_term_is_unconfirmed():
    """The ballistic fit fits the measurements (chi-square 2 per observation) but lies 5 sigma from
    the prior (term 25); the burn fit lowers the prior's term to 0 and the measurements' chi-square
    by 2 only: a burn before the arc's start, or a prior that is off, explains the arc as well."""
    b = _burn()
    found = _found([b], [(0.5, 1.5)], chi2_each=1.9, prior=PRIOR)
    why = _doubt(found, [b], 2.0, _ballistic(2.0, [5.0, 0, 0, 0, 0, 0]))
    assert why.startswith("the measurements alone do not call for the burn")
    assert "prior's term from 25.0 to 0.0" in why


def test_a_burn_the_measurements_call_for_is_confirmed_whatever_the_priors_term():
    """The same prior's term, but the ballistic fit leaves the measurements at chi-square 4 each:
    the burn lowers their part by 42, beyond the search's threshold (23.5, 4 dof at 1e-4)."""
    b = _burn()
    found = _found([b], [(0.5, 1.5)], chi2_each=1.9, prior=PRIOR)
    assert _doubt(found, [b], 2.0, _ballistic(4.0, [5.0, 0, 0, 0, 0, 0])) == ""


def test_a_burn_whose_delta_v_another_allowed_time_contradicts_is_unconfirmed():
    """A rival burn time (cistrack.least_squares.burn_search.rival_time) that fits within 1.9 of the
    estimate's cost with a delta-v 52.8 (chi-square, 3 dof) from it: neither is determined."""
    from cistrack.least_squares.burn_search import RivalTime

    b = _burn()
    rival = RivalTime(1.2, np.array([0.0, -0.11, -0.04]), 1.9, 52.8)
    why = _doubt(_found([b], [(0.5, 1.5)]), [b], 2.0, rival=rival)
    assert why.startswith("its burn time and delta-v are not determined") and "cost +1.9" in why


def test_an_unconfirmed_estimate_keeps_its_numbers_and_says_why():
    from cistrack.evaluation.run_summary import RunSummary, maneuver_lines

    rec = _record([Detection(t=1.0, statistic=9.0, threshold=4.0)], _Estimate(_burn(), "a reason"))
    assert rec["confirmed"] is False and rec["unconfirmed_reason"] == "a reason"
    assert rec["delta_v_ms"] == pytest.approx(1.0) and rec["t_burn_sigma_days"] > 0
    line = maneuver_lines(RunSummary(run_id="r", seed=1, maneuvers=[rec]))[-1]
    assert line.endswith("unconfirmed: a reason")
    ok = _record([Detection(t=1.0, statistic=9.0, threshold=4.0)], _Estimate(_burn()))
    assert ok["confirmed"] is True and "unconfirmed_reason" not in ok


def _burn_run(seed, *settings):
    from cistrack.runs.pipeline import run_scenario
    from cistrack.scenario.loading import load_scenario
    from cistrack.scenario.settings import apply_settings

    sc = apply_settings(load_scenario("example-1-burn"), list(settings))
    return run_scenario(sc, seed=seed).summary.maneuvers


def _big_burn_run(seed):
    (m,) = _burn_run(seed, "truth.maneuvers.delta_v_ms=100")
    return m


def test_a_100_ms_burn_split_over_two_burns_is_not_confirmed_with_a_zero_time_sigma():
    """example-1-burn seed 3 at 100 m/s: 17.6 m/s at 3.116 d and 82 m/s at 3.840 d for one burn at
    3.620 d; it had been confirmed as 82 +- 0.14 m/s at 3.840 +- 0 d."""
    m = _big_burn_run(3)
    assert not m["confirmed"] and "split the change over 2 burns" in m["unconfirmed_reason"]
    assert m["t_burn_sigma_days"] > 0


def test_a_100_ms_burn_whose_fit_leaves_large_residuals_is_not_confirmed():
    """example-1-burn seed 2 at 100 m/s: had been confirmed as 111 +- 0.65 m/s (17 sigma off). With
    the time profile's fits started from the estimate's rejected observations the search goes on to
    split the change over two burns (87 m/s at 3.557 d, 16 m/s at 3.990 d); either reason leaves it
    unconfirmed."""
    m = _big_burn_run(2)
    assert not m["confirmed"]
    assert m["unconfirmed_reason"].startswith(("the fit with the burn does not fit", "the search split the change"))


def test_a_burn_before_the_arcs_start_is_not_confirmed_in_a_later_gap():
    """example-1-burn seed 2 with 2 m/s at 2.0 d: the filter's first settled posterior, where the arc
    starts, is at 2.094 d, after the burn; the ballistic fit fits the arc's measurements and only the
    prior's term called for a burn. It had been confirmed as 9.8 +- 2.4 m/s at 2.330 d (3.3 sigma
    off, nearly the opposite direction); the numbers are still given."""
    (m,) = _burn_run(2, "truth.maneuvers.t_days=2.0", "truth.maneuvers.delta_v_ms=2")
    assert not m["confirmed"] and m["unconfirmed_reason"].startswith("the measurements alone do not call for the burn")
    assert m["delta_v_ms"] > 0 and m["t_burn_days"] > 2.0


def test_a_station_keeping_burn_whose_time_the_arc_does_not_place_is_not_confirmed():
    """example-1-maneuver seed 2 with 3,000 particles: its second 0.1 m/s burn (13.133 d) had been
    confirmed as 0.199 +- 0.072 m/s at 11.564 +- 0.68 d along +x (the truth: -y), though a burn
    anywhere in 11.4-14.2 d fits within 4.3 of its cost; the first burn's estimate stays confirmed.
    Where the search's minimum falls in that flat stretch depends on the last bits of the
    arithmetic: on some machines at the arc's start (11.424 d), which the start-of-arc rule refuses
    to confirm for its own reason."""
    from cistrack.runs.pipeline import run_scenario
    from cistrack.scenario.loading import load_scenario
    from cistrack.scenario.settings import apply_settings

    sc = apply_settings(load_scenario("example-1-maneuver"), ["filter.n_particles=3000", "iod.n_particles=3000"])
    first, second = run_scenario(sc, seed=2).summary.maneuvers
    assert first["confirmed"] and abs(first["delta_v_ms"] - 0.1) < 3 * first["delta_v_sigma_ms"]
    reason = second["unconfirmed_reason"]
    assert not second["confirmed"]
    assert reason.startswith("its burn time and delta-v are not") or "is the start of its arc" in reason


def test_a_station_keeping_burn_put_at_its_arcs_start_is_not_confirmed():
    """example-1-maneuver seed 2713: its first 0.1 m/s burn (6.566 d) was detected at 9.352 d, the arc
    started at 7.218 d, after the burn, and the search put the change at that instant; it had been
    confirmed as 7.218 +- 0.136 d (4.8 sigma late). The numbers are still given."""
    from cistrack.runs.pipeline import run_scenario
    from cistrack.scenario.loading import load_scenario

    first = run_scenario(load_scenario("example-1-maneuver"), seed=2713).summary.maneuvers[0]
    assert not first["confirmed"] and "is the start of its arc" in first["unconfirmed_reason"]
    assert first["delta_v_ms"] > 0 and first["t_burn_days"] > 7.2
