"""A study's efficiency: RMS position error over runs divided by the RMS information bound, at the
end of each pass and of the run; every run with both numbers counts."""
from __future__ import annotations

import math

import pytest

from cistrack.evaluation.run_summary import RunSummary
from cistrack.studies.efficiency import efficiency_text, group_efficiency


def _summary(err: float, bound: float, passes: dict[int, tuple[float, float]]) -> RunSummary:
    return RunSummary(run_id="r", seed=1, final={"pos_err_km": err, "bound_pos_km": bound},
                      pass_end={str(p): {"pos_err_km": e, "bound_pos_km": b} for p, (e, b) in passes.items()})


def test_the_ratio_is_rms_error_over_rms_bound_at_the_end_and_at_each_pass():
    sums = [_summary(3.0, 1.0, {1: (30.0, 10.0), 2: (4.0, 2.0)}), _summary(4.0, 2.0, {1: (40.0, 20.0), 2: (2.0, 2.0)})]
    e = group_efficiency(sums)
    assert e.final == pytest.approx(math.sqrt((9 + 16) / 2) / math.sqrt((1 + 4) / 2))
    assert e.by_pass[1] == pytest.approx(math.sqrt((900 + 1600) / 2) / math.sqrt((100 + 400) / 2))
    assert e.by_pass[2] == pytest.approx(math.sqrt((16 + 4) / 2) / 2.0)
    assert e.final_runs == 2 and e.bound_km == pytest.approx(math.sqrt(2.5))


def test_a_diverged_run_counts_with_its_error():
    calm = [_summary(1.0, 1.0, {})] * 3
    assert group_efficiency(calm + [_summary(1e6, 1.0, {})]).final > 1e5


def test_runs_without_a_bound_give_no_ratio():
    e = group_efficiency([RunSummary(run_id="r", seed=1, final={"pos_err_km": 2.0})])
    assert e.final is None and efficiency_text(e) == "-"
