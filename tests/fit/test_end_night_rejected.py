"""A ballistic fit that rejects every observation of its first or last night (at least two) is
suspect: independent outliers take a whole night only by chance, a burn before the last night
takes it together. A survey fit had rejected its last tracklet, two exposures after a 10 m/s burn,
too few for the block rule or the night's median bias, and reported "converged"."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from cistrack import units
from cistrack.least_squares.burn_search import end_night_rejected, suspicion


def _fit(rejected_rows=(), last_night=2):
    """Four exposures 5 minutes apart on nights 0-2 and ``last_night`` on night 3; normalised
    residuals of noise, with ``rejected_rows`` marked rejected."""
    t = np.array([units.days_to_tu(d + k * 5.0 / 1440.0)
                  for d, n in ((0.0, 4), (1.0, 4), (2.0, 4), (3.0, last_night)) for k in range(n)])
    z = np.random.default_rng(5).standard_normal((t.size, 2)) * 0.5
    rejected = np.zeros(t.size, dtype=bool)
    rejected[list(rejected_rows)] = True
    res = SimpleNamespace(times=t, normalised=z, rejected=rejected, chi2=np.sum(z * z, axis=1))
    return SimpleNamespace(residuals=res, rms=1.0, converged=True)


def test_a_last_night_of_two_rejected_whole_makes_the_fit_suspect():
    assert suspicion(_fit(rejected_rows=(-2, -1))) == "it rejects all 2 observations of its last night"


def test_a_first_night_rejected_whole_makes_the_fit_suspect():
    assert end_night_rejected(_fit(rejected_rows=(0, 1, 2, 3))) == "it rejects all 4 observations of its first night"


def test_the_times_order_the_nights_not_the_rows():
    fit = _fit(rejected_rows=(-2, -1))
    order = np.random.default_rng(1).permutation(fit.residuals.times.size)
    for name in ("times", "normalised", "rejected", "chi2"):
        setattr(fit.residuals, name, getattr(fit.residuals, name)[order])
    assert end_night_rejected(fit) == "it rejects all 2 observations of its last night"


def test_one_rejected_observation_alone_on_its_night_is_an_outlier():
    assert suspicion(_fit(rejected_rows=(-1,), last_night=1)) == ""


def test_a_night_partly_kept_is_not_rejected_whole():
    assert end_night_rejected(_fit(rejected_rows=(-1,))) == ""


def test_a_middle_night_rejected_whole_is_bad_data_not_a_burn():
    assert suspicion(_fit(rejected_rows=(4, 5, 6, 7))) == ""


def test_an_arc_of_one_night_has_no_end_night():
    fit = _fit(rejected_rows=(-2, -1))
    fit.residuals.times = fit.residuals.times * 0.01  # every observation within minutes
    assert end_night_rejected(fit) == ""
