"""Failure said at once (issue 32, item 6): a run whose normalised innovations leave their
chi-square bounds by orders of magnitude is "diverged" at the update where the blow-up starts,
with or without a truth; healthy runs keep their verdicts. Rows are built as a run writes them
(``kind``, ``step``, ``t_days``, ``nis``, sigmas); the real-run check is in test_verdicts.py."""
from __future__ import annotations

import math

import pytest

from cistrack.errors import ConfigError
from cistrack.evaluation.custody import CustodyRule, Verdict
from cistrack.evaluation.verdicts import final_verdict, verdict_lines
from cistrack.scenario.custody_table import custody_rule


def _rows(nis: list[float], sigma_km: float = 30.0) -> list[dict]:
    """An initial row, then one predict and one update row per NIS value, 0.1 day apart."""
    rows = [{"kind": "initial", "step": 0, "t_days": 0.0}]
    for i, v in enumerate(nis):
        rows.append({"kind": "predict", "step": 2 * i + 1, "t_days": 0.1 * (i + 1) - 0.05})
        rows.append({"kind": "update", "step": 2 * i + 2, "t_days": 0.1 * (i + 1), "nis": v,
                     "sigma_x_km": sigma_km, "sigma_y_km": sigma_km, "sigma_z_km": sigma_km, "entropy": 10.0,
                     "pos_err_km": 20.0, "nees": 4.0})
    return rows


# healthy for four updates, then the innovations blow up from the fifth (step 10) to the end
BLOWN = [2.1, 0.7, 3.3, 1.2, 4.0e11, 2.0e12, 8.0e13, 1.0e14, 3.0e15, 1.0e16]


def test_a_sustained_blow_up_is_diverged_at_its_first_update_without_a_truth():
    v = final_verdict(Verdict(), _rows(BLOWN), CustodyRule(), has_truth=False)
    assert v.kind == "diverged" and (v.step, v.t_days) == (10, pytest.approx(0.5))
    assert v.reason.startswith("innovations blew up: NIS 4e+11 at this update and above 1e+06 on 3 consecutive updates")


def test_a_sustained_blow_up_is_diverged_at_its_first_update_with_a_truth():
    v = final_verdict(Verdict(), _rows(BLOWN), CustodyRule(), has_truth=True)
    assert v.kind == "diverged" and (v.step, v.t_days) == (10, pytest.approx(0.5))


def test_the_verdict_line_says_the_step_and_time_where_the_blow_up_starts():
    class Summary:
        has_truth, consistency = False, {}
        verdict = final_verdict(Verdict(), _rows(BLOWN), CustodyRule(), has_truth=False)
    head = verdict_lines(Summary())[0]
    assert head.startswith("  verdict: diverged at step 10 (t = 0.5 d): innovations blew up")


def test_a_custody_loss_before_the_blow_up_keeps_its_own_time():
    lost = Verdict("lost", "truth outside the 0.997 highest-density region on 2 consecutive updates", 6, 0.3)
    v = final_verdict(lost, _rows(BLOWN), CustodyRule(), has_truth=True)
    assert v.kind == "diverged" and (v.step, v.t_days) == (6, 0.3)
    assert v.reason.startswith("innovations blew up") and "custody lost first at step 6" in v.reason


def test_fewer_consecutive_blown_updates_than_the_rule_asks_are_not_a_blow_up():
    nis = [2.1, 0.7, 5.0e7, 4.0e8, 1.3, 2.2, 7.0e9, 0.9, 1.1, 2.0]   # two outliers, then one
    assert final_verdict(Verdict(), _rows(nis), CustodyRule(), has_truth=True).kind == "tracking"


def test_updates_without_an_nis_neither_count_nor_break_a_blow_up():
    nis = [1.0, 2.0e7, math.nan, 3.0e7, 4.0e7, 1.0]
    v = final_verdict(Verdict(), _rows(nis), CustodyRule(), has_truth=True)
    assert v.kind == "diverged" and v.step == 4


def test_an_infinite_nis_counts_as_blown():
    nis = [1.0, math.inf, math.inf, math.inf]
    assert final_verdict(Verdict(), _rows(nis), CustodyRule(), has_truth=True).step == 4


def test_a_large_but_plausible_nis_of_an_outlier_train_stays_below_the_default_threshold():
    # 100 arcsec displacements at 0.5 arcsec sigma: NIS about 4e4 on every update
    v = final_verdict(Verdict(), _rows([4.0e4] * 10), CustodyRule(), has_truth=True)
    assert v.kind == "tracking"


def test_the_blow_up_threshold_and_count_are_keys_of_the_custody_table():
    rule = custody_rule({"blowup_nis": 1e4, "blowup_nis_updates": 2}, "s.toml")
    assert (rule.blowup_nis, rule.blowup_nis_updates) == (1e4, 2)
    v = final_verdict(Verdict(), _rows([1.0, 2.0e4, 3.0e4, 1.0]), rule, has_truth=True)
    assert v.kind == "diverged" and v.step == 4


def test_an_infinite_threshold_turns_the_blow_up_rule_off():
    rule = custody_rule({"blowup_nis": math.inf}, "s.toml")
    v = final_verdict(Verdict(), _rows(BLOWN), rule, has_truth=True)
    assert v.kind == "tracking"


@pytest.mark.parametrize("key, value, words", [("blowup_nis", 0.0, "> 0"), ("blowup_nis", "big", "expected int or float"),
                                               ("blowup_nis_updates", 0, ">= 1"), ("blowup_nis_updates", 1.5, "expected int")])
def test_a_bad_blow_up_setting_is_refused_naming_the_file_table_key_and_what_is_allowed(key, value, words):
    with pytest.raises(ConfigError) as err:
        custody_rule({key: value}, "s.toml")
    msg = str(err.value)
    assert msg.startswith("s.toml: [custody]: key ") and repr(key) in msg and words in msg, msg
