"""The NIS bounds' chi-square quantile agrees with scipy.stats.chi2.ppf without importing scipy
(issue 15: scipy.stats costs ~0.7 s of CPU at the end of every run; issue 51: scipy.special
another 0.1 s in every process)."""
from __future__ import annotations

import math

import pytest
from scipy.stats import chi2

from cistrack.evaluation.consistency import chi2_ppf


@pytest.mark.parametrize("dof", [1, 2, 6, 58, 2 * 29, 1000])
@pytest.mark.parametrize("q", [0.025, 0.05, 0.5, 0.95, 0.975])
def test_quantile_agrees_with_scipy_stats_to_rounding(q, dof):
    assert chi2_ppf(q, dof) == pytest.approx(chi2.ppf(q, dof), rel=1e-13)


def test_two_degrees_of_freedom_has_the_closed_form():
    # chi2(2) is exponential with mean 2: ppf(q) = -2 ln(1 - q)
    assert chi2_ppf(0.9, 2) == pytest.approx(-2.0 * math.log(0.1), rel=1e-15)
