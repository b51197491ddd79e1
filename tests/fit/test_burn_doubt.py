"""A fit with burns is reported as their measurement only when it is one: each burn's magnitude
beyond 3 of its sigmas, its time's uncertainty measured, and the fit with the burns rejecting no
more than outliers explain. Unseen survey sets (0.5 m/s) had been reported clean with a 1.33 m/s
burn whose time sigma was 0 (its fits either side failed), a 3.7 m/s burn a night early rejecting
8 of 75 observations, and a burn 21 sigma early rejecting 4 of 50."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from cistrack.fitting.maneuver_search import _burn_doubt, _rejects_too_many
from cistrack.least_squares.impulse_fit import BurnEstimate


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


def test_a_fit_with_burns_that_rejects_more_than_five_percent_is_doubted():
    assert "it still rejects 8 of 75 observations (11 %)" in _burn_doubt(_fit(75, 8), [_burn()])


def test_the_rejection_rule_needs_at_least_four():
    """Three of 40 (7.5 %) is what a survey set's injected outliers alone can be."""
    assert _rejects_too_many(_fit(40, 3)) == "" and _rejects_too_many(_fit(40, 4)) != ""
    assert _rejects_too_many(_fit(100, 5)) != "" and _rejects_too_many(_fit(100, 4)) == ""
