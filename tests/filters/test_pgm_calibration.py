"""Statistical calibration of the default PGM on the paper's Example 1 (slow).

The seeds are drawn fresh whenever this test or the PGM changes and are never used for tuning
(tuning used seeds 1-60 and 1000-1099; the acceptance figures in issue 16 used 1000-1099 for
the iterated-update version and 2000-2099 for the version with shrunk components). Current
draw: 6000-6019, drawn for the shrunk-component PGM (5000-5019 served the version before it).
Over M runs, a consistent filter keeps custody in (almost) all, its final NEES summed over runs
is chi-square with 6M degrees of freedom, and no run ends far from the truth.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2

from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario

SEEDS = range(6000, 6020)

# Measured when these seeds were drawn (kept_spread 0.7, 2026-11-23): all three tests passed for
# both IODs; on seeds 2000-2099 the default kept custody in 98/100 (uniform) and 95/100 (noisy),
# final NEES 90th percentile 9.0 / 9.9 (issue 16's note).


@pytest.fixture(scope="module", params=["uniform-range", "noisy-range"])
def finals(request):
    scenario = load_scenario("example-1").with_overrides({"iod": {"name": request.param}})
    return [run_scenario(scenario, seed=s).summary for s in SEEDS]


@pytest.mark.slow
def test_default_pgm_keeps_custody_on_fresh_seeds(finals):
    assert sum(s.custody_kept for s in finals) >= len(finals) - 1


@pytest.mark.slow
def test_default_pgm_final_anees_is_inside_the_chi2_band(finals):
    m = len(finals)
    lo, hi = chi2.ppf([0.005, 0.995], 6 * m) / m
    nees = np.array([s.final["nees"] for s in finals])
    # a lost run's NEES is not bounded: clip so that one loss (allowed above) cannot dominate
    assert lo <= np.mean(np.minimum(nees, 50.0)) <= hi, nees


@pytest.mark.slow
def test_default_pgm_never_ends_far_from_the_truth(finals):
    assert max(s.final["pos_err_km"] for s in finals) < 50.0
