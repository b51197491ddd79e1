"""The NIS bounds' chi-square quantile equals scipy.stats.chi2.ppf without importing scipy.stats
(issue 15: scipy.stats costs ~0.7 s of CPU at the end of every run)."""
from __future__ import annotations

import pytest
from scipy.stats import chi2

from cistrack.evaluation.consistency import chi2_ppf


@pytest.mark.parametrize("dof", [1, 2, 6, 58, 2 * 29, 1000])
@pytest.mark.parametrize("q", [0.025, 0.05, 0.5, 0.95, 0.975])
def test_quantile_equals_scipy_stats(q, dof):
    assert chi2_ppf(q, dof) == chi2.ppf(q, dof)


def test_two_degrees_of_freedom_has_the_closed_form():
    # chi2(2) is exponential with mean 2: ppf(q) = -2 ln(1 - q)
    import math
    assert chi2_ppf(0.9, 2) == pytest.approx(-2.0 * math.log(0.1), rel=1e-13)
