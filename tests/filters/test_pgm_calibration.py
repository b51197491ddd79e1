"""Statistical calibration of the default PGM on the paper's Example 1 (slow).

The seeds are drawn fresh whenever this test or the PGM changes and are never used for tuning
(tuning used seeds 1-60 and 1000-1099; the acceptance figures in issue 16 used 1000-1099,
then 2000-2099 for the version that splits clusters at sharp measurements). Current draw:
6000-6019 (drawn for the split version; 5000-5019 served the version before it). Over M runs, a consistent filter keeps custody in (almost) all, its final NEES
summed over runs is chi-square with 6M degrees of freedom, and no run ends far from the truth.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2

from cistrack.run import run_scenario
from cistrack.scenario import load_scenario

SEEDS = range(6000, 6020)

# Issue 16 is not met yet: on unseen seeds 1000-1099 the default PGM kept custody in 90/100
# (uniform range) and 83/100 (noisy range), final NEES 90th percentile 15.4 / 19.0. These
# two tests state the target and are expected to fail until the drift towards overconfidence
# over passes 4-6 is fixed; remove the marker then.
NOT_YET_CALIBRATED = pytest.mark.xfail(reason="issue 16: PGM still overconfident late in "
                                       "Example 1 (90/100 and 83/100 custody on seeds 1000-1099)")


@pytest.fixture(scope="module", params=["uniform-range", "noisy-range"])
def finals(request):
    scenario = load_scenario("example-1").with_overrides({"iod": {"name": request.param}})
    return [run_scenario(scenario, seed=s).summary for s in SEEDS]


@pytest.mark.slow
@NOT_YET_CALIBRATED
def test_default_pgm_keeps_custody_on_fresh_seeds(finals):
    assert sum(s.custody_kept for s in finals) >= len(finals) - 1


@pytest.mark.slow
@NOT_YET_CALIBRATED
def test_default_pgm_final_anees_is_inside_the_chi2_band(finals):
    m = len(finals)
    lo, hi = chi2.ppf([0.005, 0.995], 6 * m) / m
    nees = np.array([s.final["nees"] for s in finals])
    # a lost run's NEES is not bounded: clip so that one loss (allowed above) cannot dominate
    assert lo <= np.mean(np.minimum(nees, 50.0)) <= hi, nees


@pytest.mark.slow
def test_default_pgm_never_ends_far_from_the_truth(finals):
    assert max(s.final["pos_err_km"] for s in finals) < 50.0
