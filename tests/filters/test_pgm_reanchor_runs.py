"""The PGM's re-anchoring in whole runs (plugins/filters/pgm/reanchoring.py through pgm/filter.py): the belief
after a re-anchoring is as sharp as the information bound says the data allow, and still holds
the truth. Real scenarios, real components; the slow cases are the paper's examples."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack import api

CHI2_6_99 = 16.81


def _run(name: str, seed: int, **filter_settings):
    settings = {f"filter.{k}": v for k, v in filter_settings.items()}
    return api.run(name, seed=seed, settings=settings)


def _reanchored_rows(run) -> list[dict]:
    return [r for r in run.rows if r.get("diag_reanchored") == 1.0]


def test_quick_scenario_re_anchors_at_a_pass_end_and_stays_consistent():
    run = _run("quick", 1)
    assert _reanchored_rows(run)
    final = run.rows[-1]
    assert final["nees"] < CHI2_6_99


def test_no_re_anchoring_when_it_is_off():
    run = _run("quick", 1, reanchor="off")
    assert not _reanchored_rows(run)


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_re_anchoring_holds_example_1_at_the_bound(seed):
    run = _run("example-1", seed)
    final = run.rows[-1]
    assert final["nees"] < CHI2_6_99
    assert final["sigma_pos_km"] < 1.5 * final["bound_pos_km"]


@pytest.mark.slow
def test_re_anchoring_across_the_10_day_gap_keeps_example_2_near_the_bound():
    run = _run("example-2", 3003)                   # 70.4 km at the end without re-anchoring
    final = run.rows[-1]
    assert final["pos_err_km"] < 20.0
    assert final["sigma_pos_km"] < 2.0 * final["bound_pos_km"]
    assert np.isfinite(final["nees"]) and final["nees"] < CHI2_6_99


def _kernel_rows(run) -> list[dict]:
    return [r for r in run.rows if r.get("diag_kernel_update") == 1.0]


def test_kernel_updates_are_off_by_default():
    assert not _kernel_rows(_run("quick", 1))


def test_kernel_updates_in_passes_after_gaps_end_consistent():
    # a day between passes counts as a gap here: every pass after the first is kernel-updated
    run = _run("quick", 1, kernel_ess=1.0, reanchor_gap_days=0.5)
    assert _kernel_rows(run)
    assert run.rows[-1]["nees"] < CHI2_6_99


def test_kernel_updates_wait_for_a_pass_after_a_gap():
    run = _run("quick", 1, kernel_ess=1.0)  # three days without a 5-day gap
    assert not _kernel_rows(run)


def test_the_pass_after_a_gap_ends_at_the_next_pause():
    from cistrack.plugins.filters.pgm.kernel_update import PassAfterGap
    from cistrack.units import days_to_tu, hours_to_tu

    passes = PassAfterGap(gap_days=5.0, pause_hours=3.0)
    t = [0.0, float(hours_to_tu(0.7))]
    t += [t[-1] + float(days_to_tu(10.0)), t[-1] + float(days_to_tu(10.0) + hours_to_tu(0.7))]
    t += [t[-1] + float(hours_to_tu(5.0))]
    assert [passes.at(x) for x in t] == [False, False, True, True, False]


@pytest.mark.slow
def test_example_3_keeps_custody_where_the_first_post_gap_updates_lost_it():
    run = _run("example-3", 3029)  # diverged to 1,083 km with cluster updates after the gap
    final = run.rows[-1]
    assert run.verdict.kind == "tracking"
    assert final["pos_err_km"] < 20.0 and final["nees"] < CHI2_6_99


@pytest.mark.slow
def test_example_3_holds_the_truth_in_the_bent_valley_after_the_gap():
    run = _run("example-3", 3007)  # least squares 20 km from the truth, 80 sigmas off its covariance
    final = run.rows[-1]
    assert final["pos_err_km"] < 20.0 and final["nees"] < CHI2_6_99
