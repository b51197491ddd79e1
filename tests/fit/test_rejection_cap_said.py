"""When the cap on rejections (max_reject_fraction) keeps observations above the rejection
threshold, the fit says so: it had printed a rule ("rejected: chi-square > 0.166") that 56 of the
observations it used broke."""
from __future__ import annotations

import math

import numpy as np

from cistrack.least_squares import FitOptions, fit_orbit

from .arcs import GUESS_OFFSET, cr3bp_arc


def _fit(reject_sigma: float):
    arc = cr3bp_arc()
    ms = arc.noisy(3)
    opts = FitOptions(reject_sigma=reject_sigma, robust_threshold=False, max_reject_fraction=0.2)
    return fit_orbit(arc.dynamics, arc.sensor, ms, arc.truth0 + GUESS_OFFSET, 0.0, options=opts)


def test_observations_kept_above_the_threshold_by_the_cap_are_counted_and_the_cap_named():
    fit = _fit(0.1)
    line = next(m for m in fit.messages if "observations rejected (chi-square >" in m)
    kept = int(np.sum(np.asarray(fit.residuals.chi2)[~np.asarray(fit.residuals.rejected)] > fit.rejection_threshold))
    assert kept > 0 and f"{kept} more exceed it but are kept" in line and "fit.max_reject_fraction" in line


def test_no_such_words_when_the_cap_did_not_bind():
    fit = _fit(3.0)
    assert not any("more exceed it" in m for m in fit.messages)


def test_a_reject_sigma_below_two_is_named_with_the_share_of_noise_it_rejects():
    fit = _fit(0.3)
    line = next(m for m in fit.messages if "observations rejected (chi-square >" in m)
    noise = 100.0 * (1.0 - math.erf(0.3 / math.sqrt(2.0)))  # 2 (1 - Phi(0.3)): 76 %
    assert "fit.reject_sigma = 0.3 (default 3)" in line and f"{noise:.0f} % of observations" in line


def test_the_default_reject_sigma_is_not_named():
    fit = _fit(3.0)
    assert not any("fit.reject_sigma" in m for m in fit.messages)
