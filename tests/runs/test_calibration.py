"""Calibration statistics of a study group, against independent numbers (published tables,
closed forms, scipy's own implementations)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from cistrack.studies.calibration import anees_bounds, group_calibration, uniformity_ks, wilson_interval
from cistrack.evaluation.custody import Verdict
from cistrack.evaluation.run_summary import RunSummary


@pytest.mark.parametrize("k, n, lo, hi", [
    (81, 263, 0.2553, 0.3662),   # Newcombe (1998), Stat. Med. 17:857, worked examples, Wilson score method
    (15, 148, 0.0624, 0.1605),
    (0, 20, 0.0, 0.1611),
    (1, 29, 0.0061, 0.1718),
])
def test_wilson_interval_matches_newcombes_published_examples(k, n, lo, hi):
    assert wilson_interval(k, n) == pytest.approx((lo, hi), abs=1e-4)


@pytest.mark.parametrize("k, n", [(97, 100), (100, 100), (3, 7), (50, 50)])
def test_wilson_interval_matches_scipy_binomtest(k, n):
    from scipy.stats import binomtest

    ci = binomtest(k, n).proportion_ci(0.95, method="wilson")
    assert wilson_interval(k, n) == pytest.approx((ci.low, ci.high), abs=1e-12)


def test_wilson_interval_refuses_impossible_counts():
    with pytest.raises(ValueError, match="0 <= k <= n"):
        wilson_interval(5, 4)


def test_anees_bounds_of_one_run_are_the_chi_square_6_quantiles():
    assert anees_bounds(1) == pytest.approx((1.2373, 14.4494), abs=1e-4)  # chi-square table, 6 dof


def test_anees_bounds_of_100_runs_bracket_6_and_shrink_as_one_over_root_n():
    from scipy.stats import chi2

    lo, hi = anees_bounds(100)
    assert (lo, hi) == pytest.approx((chi2.ppf(0.025, 600) / 100, chi2.ppf(0.975, 600) / 100))
    assert lo < 6.0 < hi
    # normal approximation of chi2(600)/100: mean 6, sd sqrt(2*600)/100
    assert hi - lo == pytest.approx(2 * 1.96 * math.sqrt(1200) / 100, rel=0.02)


def test_ks_statistic_of_a_small_sample_is_the_hand_computed_distance():
    d, _ = uniformity_ks([0.7, 0.1, 0.4])
    # empirical cdf 1/3, 2/3, 1 at 0.1, 0.4, 0.7: largest gap is 1 - 0.7 = 0.3
    assert d == pytest.approx(0.3)


def test_ks_p_value_of_one_value_is_the_closed_form():
    # n = 1: D = max(x, 1 - x), P(D >= d) = 2 (1 - d) for d in [0.5, 1]
    d, p = uniformity_ks([0.9])
    assert (d, p) == pytest.approx((0.9, 0.2))


def test_ks_rejects_levels_piled_up_in_the_tail_and_keeps_uniform_ones():
    rng = np.random.default_rng(20261123)
    assert uniformity_ks(rng.uniform(size=200))[1] > 1e-3
    assert uniformity_ks(rng.uniform(0.9, 1.0, size=50))[1] < 1e-10


def test_ks_without_a_finite_value_is_nan():
    d, p = uniformity_ks([None, float("nan")])
    assert math.isnan(d) and math.isnan(p)


def _summary(i: int, kind: str, nees: float, hdr: float) -> RunSummary:
    return RunSummary(run_id=f"r{i}", seed=i, verdict=Verdict(kind), final={"nees": nees, "hdr_level": hdr})


def test_group_calibration_counts_custody_diverged_and_averages_final_nees():
    sums = [_summary(1, "tracking", 4.0, 0.2), _summary(2, "not-converged", 8.0, 0.6),
            _summary(3, "lost", float("nan"), 0.999), _summary(4, "diverged", 1e38, 1.0)]
    c = group_calibration(sums)
    assert (c.runs, c.custody_kept, c.diverged) == (4, 2, 1)
    assert (c.custody_lo, c.custody_hi) == pytest.approx(wilson_interval(2, 4))
    assert c.final_anees_runs == 3 and c.final_anees == pytest.approx((4.0 + 8.0 + 1e38) / 3)
    assert (c.final_anees_lo, c.final_anees_hi) == pytest.approx(anees_bounds(3))
    assert c.anees_within is False
    assert (c.hdr_runs, c.hdr_above_099) == (4, 0.5)
    assert (c.hdr_ks, c.hdr_ks_p) == pytest.approx(uniformity_ks([0.2, 0.6, 0.999, 1.0]))
