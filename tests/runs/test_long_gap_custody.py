"""Custody after a long gap (slow): the paper's Example 3 (3:1 NRHO, noisy-range IOD, 24 h of
measurements, then a 150-day shutoff and one more pass) with the default PGM, built-in
scenario as shipped, on fresh seeds.

The seeds are drawn fresh whenever the scenario's filter changes and were never used while
tuning it (tuning: 1-60 and 3000-3029; one-off checks on 3100-3289; this test's earlier seeds:
7000-7009). Issue 16 asks for custody in at least 90% of the runs; 8 of 10 leaves room for
sampling noise (a filter keeping custody 95% of the time passes with probability 0.99).
"""
from __future__ import annotations

import pytest

from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario

SEEDS = range(8000, 8010)

# Measured with the scenario as shipped (shrinkage only within 10 noise sigmas, 40 components at
# sharp measurements, 20,000 particles): custody in 8 of these 10 seeds (8002 and 8004 lost in the
# pass after the gap), 7 tracking. The kept runs are consistent but end 12-129 km from the truth
# with position sigmas up to about 100 km: one post-gap pass does not pin the state down further.
LESS_PRECISE = pytest.mark.xfail(reason="issue 16: after the 150-day gap the kept runs end 12-129 "
                                 "km from the truth (seeds 8000-8009)")


@pytest.fixture(scope="module")
def example3_summaries():
    scenario = load_scenario("example-3")
    return [run_scenario(scenario, seed=s).summary for s in SEEDS]


@pytest.mark.slow
def test_example3_keeps_custody_after_the_150_day_gap_on_fresh_seeds(example3_summaries):
    kept = [s.seed for s in example3_summaries if s.custody_kept]
    assert len(kept) >= 8, [(s.seed, s.verdict) for s in example3_summaries]


@pytest.mark.slow
@LESS_PRECISE
def test_example3_runs_that_keep_custody_end_within_50_km(example3_summaries):
    errs = [s.final["pos_err_km"] for s in example3_summaries if s.custody_kept]
    assert max(errs) < 50.0, errs
