"""Loss times (issue 29, item 3): a run that was lost and then diverged keeps the time the custody
rule first fired; a run that keeps custody has no loss time; a run that diverged without being lost
first is stamped where the divergence was found. Every report reads these times from the summary."""
from __future__ import annotations

import pytest

from cistrack.evaluation.custody import CustodyRule, Verdict
from cistrack.evaluation.verdicts import final_verdict
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario

RULE = CustodyRule()


def _rows(pos_err_km: float, sigma_km: float, nees: float, n: int = 6) -> list[dict]:
    return [{"kind": "update", "step": k, "t_days": 0.5 * k, "sigma_x_km": sigma_km, "sigma_y_km": sigma_km,
             "sigma_z_km": sigma_km, "pos_err_km": pos_err_km, "nees": nees, "entropy": 10.0} for k in range(1, n + 1)]


def test_lost_then_diverged_keeps_the_step_and_time_the_rule_fired():
    lost = Verdict("lost", "truth outside the 99.7 % region", 2, 1.0)
    v = final_verdict(lost, _rows(1e6, 10.0, 1e9), RULE, True)
    assert (v.kind, v.step, v.t_days) == ("diverged", 2, 1.0)
    assert "custody lost first at step 2" in v.reason and "error far beyond sigma" in v.reason


def test_diverged_without_an_earlier_loss_is_stamped_at_the_last_update():
    v = final_verdict(Verdict(), _rows(1e6, 10.0, 1e9), RULE, True)
    assert (v.kind, v.step, v.t_days) == ("diverged", 6, 3.0)


@pytest.mark.parametrize("sigma_km,kind", [(1.0, "tracking"), (RULE.precision_km * 10, "not-converged")])
def test_a_run_that_keeps_custody_has_no_loss_time(sigma_km, kind):
    v = final_verdict(Verdict(), _rows(0.5, sigma_km, 3.0), RULE, True)
    assert (v.kind, v.step, v.t_days) == (kind, None, None)


def test_lost_and_not_diverged_keeps_its_own_time():
    lost = Verdict("lost", "truth outside the 99.7 % region", 3, 1.5)
    assert final_verdict(lost, _rows(30.0, 10.0, 40.0), RULE, True) == lost


def test_a_diverged_one_shot_ukf_reports_the_time_custody_was_lost():
    """The one-shot UKF with uniform range on Example 1, seed 1, loses custody in the first pass
    and later runs away; its reported loss time is the first step whose custody column is 0."""
    scen = load_scenario("example-1").with_overrides({"filter": {"name": "ukf", "update_iterations": 1},
                                                      "iod": {"name": "uniform-range"}})
    res = run_scenario(scen, seed=1)
    s = res.summary
    first_lost = next(r for r in res.rows if r.get("custody") == 0.0)
    assert s.verdict.kind == "diverged"
    assert (s.custody_lost_step, s.custody_lost_t_days) == (first_lost["step"], first_lost["t_days"])
