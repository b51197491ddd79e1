"""Custody after a long gap (slow): the paper's Example 3 (3:1 NRHO, noisy-range IOD, 24 h of
measurements, then a 150-day shutoff and one more pass) with the default PGM, built-in
scenario as shipped, on fresh seeds.

The seeds are drawn fresh whenever the scenario's filter changes and were never used while
tuning it (tuning: 1-60 and 3000-3029; one-off checks and unseen sets on 3100-3559; this test's
earlier seeds: 7000-7009; 8000-8009 were not run with Example 3 while its session-10 filter was
built). Issue 16 asks for custody in at least 90% of the runs; 8 of 10 leaves room for
sampling noise (a filter keeping custody 95% of the time passes with probability 0.99).
"""
from __future__ import annotations

import pytest

from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario

SEEDS = range(8000, 8010)

# Measured with the scenario as shipped since session 10 (re-anchoring across the gap along the
# line of variations, kernel updates through the post-gap pass): all 10 tracking, final errors
# 1.7-13.9 km, NEES at most 14.4. Before (session 8's shipped scenario): custody in 8 of 10 (8002
# and 8004 lost in the pass after the gap), the kept runs 12-129 km from the truth.


@pytest.fixture(scope="module")
def example3_summaries():
    scenario = load_scenario("example-3")
    return [run_scenario(scenario, seed=s).summary for s in SEEDS]


@pytest.mark.slow
def test_example3_keeps_custody_after_the_150_day_gap_on_fresh_seeds(example3_summaries):
    kept = [s.seed for s in example3_summaries if s.custody_kept]
    assert len(kept) >= 8, [(s.seed, s.verdict) for s in example3_summaries]


@pytest.mark.slow
def test_example3_runs_that_keep_custody_end_within_50_km(example3_summaries):
    errs = [s.final["pos_err_km"] for s in example3_summaries if s.custody_kept]
    assert max(errs) < 50.0, errs
