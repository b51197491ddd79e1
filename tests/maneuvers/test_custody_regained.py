"""Custody that can be regained ([custody] regain_updates): lost when the truth leaves the belief,
kept again once it is back inside for that many consecutive updates; final by default."""
from __future__ import annotations

from types import SimpleNamespace

import pytest

from cistrack.errors import ConfigError
from cistrack.evaluation.custody import CustodyMetric, CustodyRule
from cistrack.scenario.custody_table import custody_rule


def _update(i: int, loglik: float):
    return SimpleNamespace(index=i, t=0.1 * i, kind="update", truth=[0.0] * 6, belief=None,
                           metrics={"truth_loglik": loglik, "hdr_level": 0.5})


def _judged(rule: CustodyRule, logliks: list[float]) -> CustodyMetric:
    c = CustodyMetric(rule)
    for i, ll in enumerate(logliks, start=1):
        c.compute(None, _update(i, ll), "updated")
    return c


OUT_THEN_BACK = [-5.0, -5.0, -900.0, -800.0, -6.0, -5.0, -4.0, -5.0]


def test_a_loss_is_final_by_default():
    c = _judged(CustodyRule(), OUT_THEN_BACK)
    assert c.verdict.kind == "lost" and c.verdict.step == 3


def test_custody_is_regained_after_the_consecutive_updates_inside():
    c = _judged(CustodyRule(regain_updates=3), OUT_THEN_BACK)
    assert c.verdict.kept
    assert "lost at step 3" in c.verdict.reason and "regained at step 7" in c.verdict.reason


def test_an_update_outside_again_restarts_the_count():
    c = _judged(CustodyRule(regain_updates=3), [-5.0, -900.0, -5.0, -5.0, -900.0, -5.0, -5.0])
    assert c.verdict.kind == "lost"


def test_regain_updates_must_be_a_count():
    with pytest.raises(ConfigError, match="regain_updates"):
        custody_rule({"regain_updates": -1}, "s.toml")
    assert custody_rule({"regain_updates": 2}, "s.toml").regain_updates == 2


def test_a_final_loss_says_when_the_truth_is_back_inside_the_belief_to_the_end():
    c = _judged(CustodyRule(), OUT_THEN_BACK)
    assert c.verdict.kind == "lost" and c.verdict.step == 3
    assert "back inside the belief on every update since step 5" in c.verdict.reason
    assert "4 updates" in c.verdict.reason and "regain_updates = 0" in c.verdict.reason


def test_a_final_loss_with_the_truth_outside_at_the_end_says_nothing_of_a_return():
    c = _judged(CustodyRule(), OUT_THEN_BACK + [-900.0])
    assert c.verdict.kind == "lost" and "back inside" not in c.verdict.reason
