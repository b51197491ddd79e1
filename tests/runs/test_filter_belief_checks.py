"""The run holds a filter to its belief after every predict and update: a belief that is not at
the step's time, or whose mean or covariance is NaN or infinite, or a documented diagnostic (a
count or size) that is not a finite number >= 0, stops the run as "filter-failed" naming the
filter and the step, rather than measuring a stale or undefined belief against the truth (custody
had stayed 1.0 on rows of NaN and the divergence had been dated ten steps late). So does a filter
that raises its own exception, naming the method too (it had ended "failed" naming neither)."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.evaluation.custody import CustodyMetric
from cistrack.model.belief import Belief, GaussianMixture
from cistrack.plugin.hookspecs import hookimpl
from cistrack.plugin.registry import load_registry
from cistrack.plugins.filters.ukf import UKFFilter
from cistrack.runs.pipeline import run_scenario
from cistrack.runs.run_context import Step
from cistrack.scenario.loading import load_scenario


class Counting(UKFFilter):
    """A UKF counting its updates in ``_n``."""

    def update(self, m):
        super().update(m)
        self._n = getattr(self, "_n", 0) + 1


class LateNaN(Counting):
    """A UKF whose belief mean turns NaN from its third update on."""

    @property
    def belief(self):
        b = super().belief
        if getattr(self, "_n", 0) < 3:
            return b
        g = b.mixture
        return Belief(b.epoch, GaussianMixture(g.weights, g.means * np.nan, g.covariances), b.samples)


class Stale(Counting):
    """A UKF whose belief stops at the epoch of its third update."""

    def update(self, m):
        super().update(m)
        if self._n == 3:
            self._frozen = super().belief

    @property
    def belief(self):
        return getattr(self, "_frozen", None) or super().belief


class NaNCount(Counting):
    """A UKF whose diagnostics give a NaN particle count from its second update on."""

    @property
    def diagnostics(self):
        return {**super().diagnostics, "n_particles": float("nan") if getattr(self, "_n", 0) >= 2 else 13.0}


class NegativeCount(UKFFilter):
    """A UKF whose diagnostics give a negative particle count."""

    @property
    def diagnostics(self):
        return {**super().diagnostics, "n_particles": -5.0}


class RaisesInUpdate(Counting):
    """A UKF whose second update raises its own KeyError (a bug of the plugin)."""

    def update(self, m):
        super().update(m)
        if self._n == 2:
            raise KeyError("nope")


class ToldOfFailures:
    """An observer keeping the errors cistrack_run_failed tells it."""

    def __init__(self):
        self.errors = []

    @hookimpl
    def cistrack_run_failed(self, run, step_index, error):
        self.errors.append(error)


def _run(cls, **options):
    reg = load_registry(autoload_third_party=False)
    reg.add("filter", "h-mine", cls, "hplug", "0.1", "hplug")
    scen = load_scenario("quick", reg, overrides={"duration_days": 2.0, "filter": {"name": "h-mine"}})
    return run_scenario(scen, seed=1, registry=reg, **options)


def test_a_belief_that_turns_nan_stops_the_run_as_filter_failed_at_that_step_naming_the_filter():
    res = _run(LateNaN)
    assert res.summary.status == "filter-failed"
    assert res.summary.failure == ("FilterError: filter 'h-mine' (hplug 0.1): the belief's mean or covariance is NaN or infinite "
                                   "after update at step 3 (t = 1.161 d)")
    assert [r["step"] for r in res.rows] == [0, 1, 2]


def test_a_belief_left_at_an_earlier_time_stops_the_run_naming_both_times():
    res = _run(Stale)
    assert res.summary.status == "filter-failed"
    assert res.summary.failure.startswith("FilterError: filter 'h-mine' (hplug 0.1): belief epoch 1.161 d after predict to "
                                          "1.196 d (step 4)")


def test_a_nan_documented_diagnostic_stops_the_run_as_filter_failed_naming_the_key_value_and_step():
    res = _run(NaNCount)
    assert res.summary.status == "filter-failed"
    assert res.summary.failure.startswith("FilterError: filter 'h-mine' (hplug 0.1): diagnostic 'n_particles' = nan after update at "
                                          "step 2 (t = 1.122 d); a documented diagnostic")
    assert [r["step"] for r in res.rows] == [0, 1]


def test_a_negative_documented_diagnostic_stops_the_run_before_its_first_row():
    res = _run(NegativeCount)
    assert res.summary.status == "filter-failed"
    assert res.summary.failure.startswith("FilterError: filter 'h-mine' (hplug 0.1): diagnostic 'n_particles' = -5.0 after "
                                          "initialize at step 0")
    assert res.rows == []


def test_a_filter_raising_its_own_exception_ends_the_run_filter_failed_naming_it_the_method_and_the_step():
    res = _run(RaisesInUpdate)
    assert res.summary.status == "filter-failed"
    assert res.summary.failure == ("FilterError: filter 'h-mine' (hplug 0.1) raised KeyError: 'nope' in update at step 2 "
                                   "(t = 1.122 d)")


def test_observers_are_told_through_cistrack_run_failed_when_the_filter_raises():
    told = ToldOfFailures()
    _run(RaisesInUpdate, observers=[told])
    assert told.errors == ["FilterError: filter 'h-mine' (hplug 0.1) raised KeyError: 'nope' in update at step 2 "
                           "(t = 1.122 d)"]


def _update_step(**metrics) -> Step:
    gm = GaussianMixture(np.ones(1), np.zeros((1, 6)), np.eye(6)[None])
    return Step(index=3, t=0.27, utc="", kind="update", belief=Belief(0.27, gm, None), truth=np.zeros(6),
                metrics=metrics)


def test_custody_is_lost_where_the_truth_log_likelihood_is_nan():
    custody = CustodyMetric()
    assert custody.compute(None, _update_step(truth_loglik=float("nan"), hdr_level=0.5), "updated") == {"custody": 0.0}
    assert custody.verdict.kind == "lost" and custody.verdict.step == 3
    assert "undefined" in custody.verdict.reason


def test_custody_is_lost_where_the_hdr_level_is_nan():
    custody = CustodyMetric()
    assert custody.compute(None, _update_step(truth_loglik=-3.0, hdr_level=float("nan")), "updated") == {"custody": 0.0}
    assert custody.verdict.kind == "lost"


def test_the_filter_conformance_lifecycle_check_catches_a_belief_that_turns_nan_on_a_later_update():
    from cistrack.testing import iter_checks

    check = dict(iter_checks(LateNaN))["lifecycle_and_belief"]
    with pytest.raises(AssertionError, match="after update.* has NaN or infinity"):
        check()
