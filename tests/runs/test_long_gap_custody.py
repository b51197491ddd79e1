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

# Issue 16 is not met yet for Example 3: with the reacquisition particles the default PGM kept
# custody in 22 of the 30 unseen seeds 3000-3029 (18 of tuning seeds 1-20; 13 of 20 before),
# measured before the PGM's component shrinkage (kept_spread) was added.
# The test states the target and is expected to fail until that is fixed; remove the marker then.
NOT_YET_MET = pytest.mark.xfail(reason="issue 16: Example 3 kept custody in 22/30 unseen seeds "
                                "(3000-3029), short of 90%")


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
def test_example3_runs_that_keep_custody_end_within_50_km(example3_summaries):
    errs = [s.final["pos_err_km"] for s in example3_summaries if s.custody_kept]
    assert max(errs) < 50.0, errs
