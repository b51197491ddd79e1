"""Custody after a long gap (slow): the paper's Example 3 (3:1 NRHO, noisy-range IOD, 24 h of
measurements, then a 150-day shutoff and one more pass) with the default PGM, built-in
scenario as shipped, on fresh seeds.

The seeds were never used while tuning the PGM's reacquisition (tuning: 1-20; the issue-16
report: 3000-3029). Issue 16 asks for custody in at least 90% of the runs; 8 of 10 leaves room
for sampling noise (a filter keeping custody 95% of the time passes with probability 0.99).
"""
from __future__ import annotations

import pytest

from cistrack.run import run_scenario
from cistrack.scenario import load_scenario

SEEDS = range(7000, 7010)

# Issue 16 is not met yet for Example 3. Measured with the PGM as shipped (shrinkage, not while
# reacquiring; reacquisition particles; 20,000 particles): these seeds 8 of 10 (7001 and 7007 lost
# during the pass after the gap, ending 50 and 5 km away). With 10,000 particles, before the
# scenario took 20,000: these seeds 8 of 10 (7004 diverged), held-out seeds 3200-3229 24 of 30.
# The test states the target and is expected to fail until that is fixed; remove the marker then.
NOT_YET_MET = pytest.mark.xfail(reason="issue 16: Example 3 kept custody in 24/30 held-out seeds "
                                "(3200-3229, 10,000 particles), short of 90%")

# The component shrinkage that keeps the pass after the gap from drifting to overconfidence costs
# precision (plugins/filters/component_spread.py): the runs kept here end 14-120 km from the truth
# (position sigmas mostly above 100 km: verdict "not-converged"); without shrinkage the runs kept
# end ~14 km away (median, seeds 1-20, 10,000 particles) but more runs are lost.
LESS_PRECISE = pytest.mark.xfail(reason="issue 16: after the 150-day gap the shrinking PGM ends "
                                 "14-120 km from the truth (seeds 7000-7009)")


@pytest.fixture(scope="module")
def example3_summaries():
    scenario = load_scenario("example-3")
    return [run_scenario(scenario, seed=s).summary for s in SEEDS]


@pytest.mark.slow
@NOT_YET_MET
def test_example3_keeps_custody_after_the_150_day_gap_on_fresh_seeds(example3_summaries):
    kept = [s.seed for s in example3_summaries if s.custody_kept]
    assert len(kept) >= 8, [(s.seed, s.verdict) for s in example3_summaries]


@pytest.mark.slow
@LESS_PRECISE
def test_example3_runs_that_keep_custody_end_within_50_km(example3_summaries):
    errs = [s.final["pos_err_km"] for s in example3_summaries if s.custody_kept]
    assert max(errs) < 50.0, errs
