"""A fit with burns is reported as their measurement only when it is one: each burn's magnitude
beyond 3 of its sigmas, its time's uncertainty measured, and the fit with the burns rejecting no
more than outliers explain. Unseen survey sets (0.5 m/s) had been reported clean with a 1.33 m/s
burn whose time sigma was 0 (its fits either side failed), a 3.7 m/s burn a night early rejecting
8 of 75 observations, and a burn 21 sigma early rejecting 4 of 50."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from cistrack import units
from cistrack.fitting.maneuver_search import _burn_doubt, _rejects_too_many, least_significance
from cistrack.least_squares.impulse_fit import BurnEstimate, dv_names


def _fit(n: int, rejected: int, seed: int = 2):
    flags = np.zeros(n, dtype=bool)
    flags[np.random.default_rng(seed).choice(n, rejected, replace=False)] = True
    t = np.linspace(0.0, 2.0, n)
    res = SimpleNamespace(times=t, rejected=flags, normalised=np.random.default_rng(seed).standard_normal((n, 2)),
                          chi2=np.full(n, 2.0))
    return SimpleNamespace(residuals=res, rms=1.0, converged=True)


def _burn(t_sigma=0.01, dv_dt=np.ones(3), sigma=0.02):
    return BurnEstimate(1.0, np.array([0.3, 0.2, 0.3]), np.eye(3) * sigma ** 2, t_sigma, dv_dt)


def test_a_measured_burn_in_a_fit_that_rejects_only_outliers_is_no_doubt():
    assert _burn_doubt(_fit(75, 2), [_burn()]) == ""


def test_a_burn_time_without_a_measured_uncertainty_is_doubted():
    assert "has no measured uncertainty" in _burn_doubt(_fit(75, 1), [_burn(t_sigma=0.0, dv_dt=None)])


def test_a_burn_within_three_sigma_of_none_is_doubted():
    assert "within 3 sigma of none" in _burn_doubt(_fit(75, 1), [_burn(sigma=0.3)])


def _nights_fit(before: int, after: int):
    """A fit of four exposures a night (20 minutes apart), ``before`` nights before the burn at
    t = 1 TU and ``after`` nights after it, one day apart."""
    day, minute = units.days_to_tu(1.0), units.seconds_to_tu(60.0)
    starts = [1.0 - (k + 0.5) * day for k in range(before)] + [1.0 + (k + 0.5) * day for k in range(after)]
    t = np.sort(np.concatenate([s + np.arange(4) * 20.0 * minute for s in starts]))
    fit = _fit(t.size, 0)
    fit.residuals.times = t
    return fit


def test_a_burn_within_three_sigma_of_none_with_two_nights_each_side_is_reported():
    """Two nights on a side test a burn's four parameters; the search's test against the fit
    without it found one. Its wide sigma is its measurement (a DRO's 1 m/s: 0.86 +- 0.32 m/s)."""
    assert _burn_doubt(_nights_fit(2, 3), [_burn(sigma=0.2)]) == ""  # 0.47 m/s, 2.3 sigma


def test_a_burn_within_two_sigma_of_none_is_doubted_however_many_nights():
    """Unseen survey sets: 17 +- 170 m/s (the truth after it at Mahalanobis^2 383), 0.9 +- 140 m/s."""
    assert "within 2 sigma of none" in _burn_doubt(_nights_fit(2, 3), [_burn(sigma=0.3)])  # 1.6 sigma


def test_a_burn_within_three_sigma_of_none_with_one_night_on_a_side_is_doubted():
    """One tracklet's angles and rates fit any burn: a mis-identified tracklet passes for one."""
    assert "within 3 sigma of none" in _burn_doubt(_nights_fit(1, 3), [_burn(sigma=0.3)])
    assert "within 3 sigma of none" in _burn_doubt(_nights_fit(3, 1), [_burn(sigma=0.3)])


def test_a_fit_with_burns_that_rejects_more_than_five_percent_is_doubted():
    assert "it still rejects 8 of 75 observations (11 %)" in _burn_doubt(_fit(75, 8), [_burn()])


def test_the_rejection_rule_needs_at_least_four():
    """Three of 40 (7.5 %) is what a survey set's injected outliers alone can be."""
    assert _rejects_too_many(_fit(40, 3)) == "" and _rejects_too_many(_fit(40, 4)) != ""
    assert _rejects_too_many(_fit(100, 5)) != "" and _rejects_too_many(_fit(100, 4)) == ""


def _timed_burn(dv, at_time_sigmas, g_sigma):
    """A burn (t_sigma 1) whose time term g g^T turns its delta-v, and a fit of 135 observations
    holding the burn's at-time covariance among its parameters."""
    base = np.diag(np.square(at_time_sigmas))
    g = np.asarray(g_sigma, dtype=float)
    burn = BurnEstimate(1.0, np.asarray(dv, dtype=float), base + np.outer(g, g), 1.0, g)
    fit = _fit(135, 0)
    fit.parameter_names, fit.full_covariance = dv_names(0), np.eye(9)
    fit.full_covariance[6:, 6:] = base
    return burn, fit


def test_a_burn_time_that_turns_the_delta_v_leaves_it_measured():
    """The dense campaign's 0.3 m/s burn (+- 59 min): the time's linear term gave 0.278 +- 0.321
    m/s, yet at every time within 3 sigma |dv| is 4 or more of its sigmas (the ballistic fit had
    rejected 13 observations)."""
    burn, fit = _timed_burn([0.054, -0.026, -0.272], [0.025, 0.027, 0.015], [-0.182, 0.09, 0.284])
    assert burn.magnitude_ms < 3.0 * burn.magnitude_sigma_ms
    assert least_significance(fit, 0, burn) > 3.0
    assert _burn_doubt(fit, [burn]) == ""


def test_a_burn_time_that_shrinks_the_delta_v_to_none_is_doubted():
    burn, fit = _timed_burn([0.3, 0.0, 0.0], [0.02, 0.02, 0.02], [-0.15, 0.0, 0.0])  # |dv| 0 at t + 2 sigma
    assert least_significance(fit, 0, burn) < 1.0
    assert "within 3 sigma of none" in _burn_doubt(fit, [burn])


def test_without_the_fit_s_covariance_the_burn_s_own_is_used():
    assert least_significance(SimpleNamespace(), 0, _burn(sigma=0.3)) < 3.0
    assert least_significance(SimpleNamespace(), 0, _burn()) > 3.0


def test_a_burn_whose_size_trades_against_its_time_beyond_twice_its_size_is_doubted():
    """An unseen survey set's 0.5 m/s burn: 1.1 +- 1.2 m/s, its time +- 20 hours, the delta-v it
    needs changing by 27 m/s within one sigma of its time."""
    burn, fit = _timed_burn([0.934, -0.583, -0.034], [0.05, 0.05, 0.05], [17.945, -20.993, -0.639])
    assert "trades its size against its time" in _burn_doubt(fit, [burn])


def test_a_burn_widened_to_other_allowed_times_is_judged_by_its_whole_covariance():
    """Its time's sigma then reaches times fitted in full, far beyond where the linear term g
    holds: the size is judged in the covariance those fits widened."""
    from dataclasses import replace

    burn, fit = _timed_burn([0.934, -0.583, -0.034], [0.05, 0.05, 0.05], [0.01, 0.01, 0.0])
    assert _burn_doubt(fit, [burn]) == ""
    wide = replace(burn, covariance_ms2=burn.covariance_ms2 + np.eye(3) * 1.2 ** 2, t_sigma=20.0, widened=True)
    assert "within 3 sigma of none" in _burn_doubt(fit, [wide])
