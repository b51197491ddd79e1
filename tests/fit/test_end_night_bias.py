"""A ballistic fit whose first or last night sits off it together is suspect (a burn before the
last night, or after the first): the median normalised residual of that night's observations
(used or rejected) beyond chi-square 18.42 (2 dof, 1e-4) in the median's noise. A sparse survey
fit had followed both sides of a 0.5 m/s burn but for its last tracklet, rejecting three of its
four exposures and keeping the other, and reported "converged" with the truth 1,000 sigma away."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from cistrack import units
from cistrack.least_squares.burn_search import end_night_bias, suspicion

NIGHTS = (0.0, 1.0, 2.0, 3.0)  # days; four exposures 5 minutes apart each night


def _fit(last_night_offset=(0.0, 0.0), outlier=None, seed=3):
    t = np.array([units.days_to_tu(d + k * 5.0 / 1440.0) for d in NIGHTS for k in range(4)])
    z = np.random.default_rng(seed).standard_normal((t.size, 2))
    z[-4:] += np.asarray(last_night_offset)
    if outlier is not None:
        z[outlier] = (3000.0, -2000.0)
    rejected = np.abs(z).max(axis=1) > 3.44  # chi-square 11.83 of two components, roughly
    res = SimpleNamespace(times=t, normalised=z, rejected=rejected, chi2=np.sum(z * z, axis=1))
    return SimpleNamespace(residuals=res, rms=1.0, converged=True)


def test_a_last_night_off_the_fit_together_makes_it_suspect_though_one_exposure_is_kept():
    fit = _fit(last_night_offset=(0.0, 3.0))
    assert 0 < fit.residuals.rejected[-4:].sum() < 4  # no contiguous block to the arc's end
    assert "the 4 observations of its last night sit off it together" in suspicion(fit)


def test_a_gross_outlier_in_a_night_is_no_bias():
    assert end_night_bias(_fit(outlier=2)) == "" and end_night_bias(_fit(outlier=-1)) == ""


def test_noise_alone_is_no_bias():
    assert all(end_night_bias(_fit(seed=s)) == "" for s in range(200))
