"""A step's metrics are made in the run's metric stage, in a declared order, before any observer
sees the step; observers get them complete and cannot change them; a plugin adds metrics of its
own through ``cistrack_metric_stages`` and they become columns of the step table."""
from __future__ import annotations

import copy
import json
import pickle

import numpy as np
import pytest

from cistrack.errors import ConfigError
from cistrack.evaluation.metric_stage import MetricStage, ReadOnlyMetrics, StepMetric, order_metrics
from cistrack.plugin.hookspecs import hookimpl
from cistrack.runs.pipeline import RunOptions, run_scenario
from cistrack.scenario.loading import load_scenario


def _small():
    return load_scenario("quick").with_overrides({"duration_days": 1.4, "filter": {"n_particles": 200, "n_components": 2},
                                                  "iod": {"n_particles": 200}, "run": {"predict_every_hours": 6.0}})


class ErrorOverSigma(StepMetric):
    """A third party's metric: the position error in units of the position sigma (needs the
    ``belief`` stage's pos_err_km and sigma_pos_km)."""

    name = "error-over-sigma"
    needs = ("belief",)

    def compute(self, run, step, event):
        m = step.metrics
        return {"err_over_sigma": m["pos_err_km"] / m["sigma_pos_km"]} if "pos_err_km" in m else {}


class SquaredErrorOverSigma(StepMetric):
    """A metric of a metric: needs the third party's own ``error-over-sigma`` stage."""

    name = "squared-error-over-sigma"
    needs = ("error-over-sigma",)

    def compute(self, run, step, event):
        m = step.metrics
        return {"err_over_sigma_sq": m["err_over_sigma"] ** 2} if "err_over_sigma" in m else {}


class SigmaPlugin:
    """A plugin object adding both stages, the dependent one listed first."""

    @hookimpl
    def cistrack_metric_stages(self, scenario):
        return [SquaredErrorOverSigma(), ErrorOverSigma()]


class MetricsSeen:
    """An observer keeping a copy of the metrics of every step it is handed."""

    def __init__(self):
        self.seen: list[tuple[str, str, dict]] = []  # (hook, step kind, metrics)

    @hookimpl
    def cistrack_step_predicted(self, run, step):
        self.seen.append(("predicted", step.kind, dict(step.metrics)))

    @hookimpl
    def cistrack_step_updated(self, run, step):
        self.seen.append(("updated", step.kind, dict(step.metrics)))


@pytest.fixture(scope="module")
def run_with_plugin():
    seen = MetricsSeen()
    res = run_scenario(_small(), seed=3, observers=[SigmaPlugin(), seen])
    assert res.summary.status == "finished"
    return res, seen


def _comparable(metrics):
    """Metric name -> float, NaN as None (NaN != NaN)."""
    return {k: None if np.isnan(v) else float(v) for k, v in metrics.items()}


def _metrics_of(row):
    meta = {"run_id", "seed", "step", "kind", "t_tu", "t_days", "utc", "measurement_index"}
    return _comparable({k: v for k, v in row.items() if k not in meta and not k.startswith(("diag_", "time_"))})


def test_observers_see_every_metric_of_the_step_row(run_with_plugin):
    res, observer = run_with_plugin
    rows_seen = [m for hook, kind, m in observer.seen if hook == "updated" or kind != "update"]  # not priors
    assert len(rows_seen) == len(res.rows)
    for row, metrics in zip(res.rows, rows_seen):
        assert _comparable(metrics) == _metrics_of(row)
    updates = [m for hook, _, m in observer.seen if hook == "updated"]
    assert updates and all({"entropy", "bound_pos_km", "nis", "custody", "err_over_sigma_sq"} <= set(m) for m in updates)


def test_a_third_party_metric_is_a_column_of_the_step_table(run_with_plugin):
    res, _ = run_with_plugin
    for row in res.rows:
        assert row["err_over_sigma"] == row["pos_err_km"] / row["sigma_pos_km"]


def test_a_metric_that_needs_another_runs_after_it_and_sees_its_value(run_with_plugin):
    res, _ = run_with_plugin
    assert all(row["err_over_sigma_sq"] == row["err_over_sigma"] ** 2 for row in res.rows)


def test_the_built_in_stages_keep_their_order_and_third_party_stages_follow():
    from cistrack.evaluation.custody import CustodyMetric
    from cistrack.runs.observers import builtin_metrics

    stage = MetricStage(builtin_metrics(CustodyMetric()) + [SquaredErrorOverSigma(), ErrorOverSigma()])
    assert [s.name for s in stage.stages] == ["belief", "pass_index", "information_bound", "residuals", "custody",
                                              "error-over-sigma", "squared-error-over-sigma"]


PLUGIN_MODULE = """
from cistrack.api import hookimpl
from cistrack.evaluation.metric_stage import StepMetric


class UpdateCount(StepMetric):
    name = "update-count"

    def __init__(self):
        self.n = 0

    def compute(self, run, step, event):
        self.n += event == "updated"
        return {"updates_so_far": float(self.n)}


@hookimpl
def cistrack_metric_stages(scenario):
    return [UpdateCount()]
"""


def test_an_installed_plugin_module_adds_a_metric_column(tmp_path):
    from plugin_site import registry_with_module  # tests/ is on sys.path

    reg = registry_with_module(tmp_path, "count_plugin", PLUGIN_MODULE, "count-dist", "update-count")
    res = run_scenario(_small(), seed=3, registry=reg)
    counts = [row["updates_so_far"] for row in res.rows]
    assert counts == [float(sum(r["kind"] == "update" for r in res.rows[:i + 1])) for i in range(len(res.rows))]


class ChangesMetrics:
    """An observer that breaks the rule: it writes into the step's metrics."""

    @hookimpl
    def cistrack_step_updated(self, run, step):
        step.metrics["mine"] = 1.0


def test_an_observer_that_modifies_the_metrics_fails_the_run_loudly():
    res = run_scenario(_small(), seed=3, observers=[ChangesMetrics()])
    assert res.summary.status == "failed"
    assert "TypeError" in res.summary.failure and "read-only" in res.summary.failure
    assert all("mine" not in row for row in res.rows)


@pytest.mark.parametrize("change", [lambda m: m.update(a=2.0), lambda m: m.pop("a"), lambda m: m.setdefault("b", 1.0),
                                    lambda m: m.clear(), lambda m: m.popitem(), lambda m: m.__delitem__("a"),
                                    lambda m: m.__ior__({"b": 1.0})])
def test_read_only_metrics_refuse_every_change(change):
    m = ReadOnlyMetrics({"a": 1.0})
    with pytest.raises(TypeError, match="read-only"):
        change(m)
    assert m == {"a": 1.0}


def test_read_only_metrics_copy_pickle_and_serialise_as_a_dict():
    m = ReadOnlyMetrics({"a": 1.0, "b": np.float64(2.5)})
    for back in (copy.copy(m), copy.deepcopy(m), pickle.loads(pickle.dumps(m))):
        assert back == m and isinstance(back, ReadOnlyMetrics)
    assert json.loads(json.dumps(m)) == {"a": 1.0, "b": 2.5}
    assert dict(m) == {"a": 1.0, "b": 2.5} and type(dict(m)) is dict


class WritesEntropy(StepMetric):
    name = "entropy-again"

    def compute(self, run, step, event):
        return {"entropy": 0.0}


class StagesPlugin:
    """A plugin object adding the given stages."""

    def __init__(self, *stages: StepMetric):
        self.stages = list(stages)

    @hookimpl
    def cistrack_metric_stages(self, scenario):
        return self.stages


def test_a_stage_that_overwrites_an_earlier_stages_metric_fails_the_run_naming_it():
    res = run_scenario(_small(), seed=3, observers=[StagesPlugin(WritesEntropy())])
    assert res.summary.status == "failed"
    assert "'entropy-again' writes entropy" in res.summary.failure


class ShiftsTheCloud(StepMetric):
    name = "shifts-the-cloud"

    def compute(self, run, step, event):
        step.belief.samples.states[:, 0] += 1.0  # against the rule: a stage measures the belief
        return {}


def test_a_stage_that_writes_into_the_belief_fails_the_run_naming_it_and_the_filter_is_untouched():
    res = run_scenario(_small(), seed=3, observers=[StagesPlugin(ShiftsTheCloud())])
    assert res.summary.status == "failed"
    assert "metric stage 'shifts-the-cloud': compute() raised" in res.summary.failure
    assert "the step's belief is read-only" in res.summary.failure


class _Named(StepMetric):
    def __init__(self, name, needs=()):
        self.name, self.needs = name, tuple(needs)

    def compute(self, run, step, event):
        return {}


def test_stages_run_in_the_order_given_except_after_what_they_need():
    order = order_metrics([_Named("c", ["b"]), _Named("a"), _Named("b", ["a"]), _Named("d")])
    assert [s.name for s in order] == ["a", "b", "c", "d"]


@pytest.mark.parametrize("stages, words", [
    ([_Named("a", ["missing"])], "'a' needs 'missing', which no stage provides"),
    ([_Named("a", ["b"]), _Named("b", ["a"])], "cycle"),
    ([_Named("a"), _Named("a")], "also the name of"),
    ([_Named("")], "empty"),
])
def test_a_bad_set_of_stages_is_refused_naming_the_problem(stages, words):
    with pytest.raises(ConfigError, match=words):
        order_metrics(stages)


class NeedsMissing:
    @hookimpl
    def cistrack_metric_stages(self, scenario):
        return [_Named("orphan", ["no-such-stage"])]


def test_a_run_with_a_stage_whose_need_is_missing_is_refused_before_it_starts(tmp_path):
    with pytest.raises(ConfigError, match="'orphan' needs 'no-such-stage'"):
        run_scenario(_small(), seed=3, observers=[NeedsMissing()], output_dir=tmp_path / "r")
    assert not (tmp_path / "r").exists()


def test_run_options_and_keywords_are_the_same_run():
    a = run_scenario(_small(), seed=3, rows_per_part=5)
    b = run_scenario(_small(), options=RunOptions(seed=3, rows_per_part=5))
    c = run_scenario(_small(), options=RunOptions(seed=9), seed=3)  # a keyword wins over the options
    strip = [{k: v for k, v in r.items() if not k.startswith("time_")} for r in a.rows]
    for other in (b, c):
        assert [{k: v for k, v in r.items() if not k.startswith("time_")} for r in other.rows] == strip


def test_an_unknown_run_keyword_is_refused_listing_the_known_ones():
    with pytest.raises(TypeError, match=r"'sede'.*known: .*seed"):
        run_scenario(_small(), sede=3)


@pytest.mark.parametrize("module, old, new", [("custody", "CustodyObserver", "CustodyMetric"),
                                              ("residuals", "ResidualObserver", "ResidualMetric"),
                                              ("information_bound", "InformationBoundObserver", "InformationBoundMetric")])
def test_the_old_observer_names_still_import_with_a_deprecation_warning(module, old, new):
    import importlib

    mod = importlib.import_module(f"cistrack.evaluation.{module}")
    with pytest.warns(DeprecationWarning, match=new):
        assert getattr(mod, old) is getattr(mod, new)
