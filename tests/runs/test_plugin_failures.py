"""A plugin's metric stage or observer that breaks its contract during a run (raises, calls
sys.exit, returns what its hook does not promise) fails the run naming the stage or the plugin and
the hook: the run ends "failed" (the filter is not at fault), its manifest is completed, and no
traceback reaches the person running it."""
from __future__ import annotations

import json
import re
import signal

import numpy as np
import pytest

from cistrack.cli.signals import install_signal_handlers
from cistrack.errors import ConfigError
from cistrack.evaluation.metric_stage import StepMetric
from cistrack.plugin.hookspecs import hookimpl
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario


def _small():
    return load_scenario("quick").with_overrides({"duration_days": 1.4, "filter": {"name": "ukf"}})


class Returns(StepMetric):
    """A third party's stage returning ``value`` from compute()."""

    name, needs = "hmetric", ("belief",)

    def __init__(self, value):
        self.value = value

    def compute(self, run, step, event):
        return self.value


class Raises(StepMetric):
    name = "hmetric"

    def __init__(self, exc):
        self.exc = exc

    def compute(self, run, step, event):
        raise self.exc


class StagePlugin:
    """An observer adding ``stages`` through cistrack_metric_stages (returned as they are)."""

    def __init__(self, stages):
        self.stages = stages

    @hookimpl
    def cistrack_metric_stages(self, scenario):
        return self.stages


def _failure_with(stages, **kw):
    res = run_scenario(_small(), seed=1, observers=[StagePlugin(stages)], **kw)
    assert res.summary.status == "failed"
    return res.summary.failure


def test_a_metric_stages_hook_returning_a_bare_stage_is_refused_before_the_run_naming_the_plugin():
    with pytest.raises(ConfigError, match=r"^observer-\d-StagePlugin: cistrack_metric_stages must return a list of "
                                          r"cistrack\.api\.StepMetric objects \(or None\), got Returns"):
        run_scenario(_small(), seed=1, observers=[StagePlugin(Returns({}))])


def test_a_metric_whose_key_is_not_a_str_fails_the_run_naming_the_stage_and_the_key():
    assert _failure_with([Returns({1: 2.0})]).startswith(
        "metric stage 'hmetric': key 1 (int) is not a str: metric names are str (a stage of observer-")


def test_a_metric_value_that_is_a_string_fails_the_run_naming_the_stage_the_key_and_the_value():
    assert _failure_with([Returns({"h_label": "hello"})]).startswith(
        "metric stage 'hmetric': key 'h_label' = 'hello' is not a number")


def test_a_metric_value_that_is_an_array_fails_the_run_naming_the_stage_and_the_key():
    assert _failure_with([Returns({"h_arr": np.arange(3.0)})]).startswith(
        "metric stage 'hmetric': key 'h_arr' = array([0., 1., 2.]) is not a number")


def test_a_stage_returning_a_list_fails_the_run_saying_what_it_must_return():
    assert _failure_with([Returns([("a", 1.0)])]).startswith(
        "metric stage 'hmetric': compute() must return a dict of str -> float, got list")


def test_a_stage_that_raises_fails_the_run_naming_the_stage_and_the_error():
    assert _failure_with([Raises(ValueError("metric boom"))]).startswith(
        "metric stage 'hmetric': compute() raised ValueError: metric boom")


def test_a_stage_that_calls_sys_exit_fails_the_run_and_completes_its_manifest(tmp_path):
    failure = _failure_with([Raises(SystemExit(5))], output_dir=tmp_path / "run")
    assert failure.startswith("metric stage 'hmetric': compute() raised SystemExit: it called sys.exit(5)")
    assert json.loads((tmp_path / "run" / "manifest.json").read_text())["status"] == "failed"


def test_a_stage_raising_generator_exit_fails_the_run_naming_the_stage_and_completes_its_manifest(tmp_path):
    """GeneratorExit is a BaseException, like SystemExit; it had ended the run in a traceback and left
    its manifest "running" (probe I1)."""
    failure = _failure_with([Raises(GeneratorExit())], output_dir=tmp_path / "run")
    assert failure.startswith("metric stage 'hmetric': compute() raised GeneratorExit")
    assert json.loads((tmp_path / "run" / "manifest.json").read_text())["status"] == "failed"


def test_a_keyboard_interrupt_a_stage_raises_under_the_commands_handlers_fails_the_run_naming_the_stage():
    """While the command's handlers are installed a Ctrl-C raises a RunInterrupted, so a plain
    KeyboardInterrupt is the plugin's own: not reported as a signal (probe I1)."""
    old = install_signal_handlers()
    try:
        failure = _failure_with([Raises(KeyboardInterrupt("the stage's own"))])
    finally:
        for sig, handler in old.items():
            signal.signal(sig, handler)
    assert failure.startswith("metric stage 'hmetric': compute() raised KeyboardInterrupt: the stage's own")


class ObserverRaises:
    """An observer whose cistrack_step_updated raises ``exc``."""

    def __init__(self, exc):
        self.exc = exc

    @hookimpl
    def cistrack_step_updated(self, run, step):
        raise self.exc


def test_an_observer_raising_in_a_step_hook_fails_the_run_naming_the_observer_and_the_hook():
    res = run_scenario(_small(), seed=1, observers=[ObserverRaises(RuntimeError("observer boom"))])
    assert res.summary.status == "failed"
    assert res.summary.failure.endswith("-ObserverRaises: cistrack_step_updated raised RuntimeError: observer boom")


def test_an_observer_calling_sys_exit_fails_the_run_naming_it_and_completes_the_manifest(tmp_path):
    res = run_scenario(_small(), seed=1, observers=[ObserverRaises(SystemExit(3))], output_dir=tmp_path / "run")
    assert res.summary.status == "failed"
    assert res.summary.failure.endswith("-ObserverRaises: cistrack_step_updated raised SystemExit: it called sys.exit(3)")
    assert json.loads((tmp_path / "run" / "manifest.json").read_text())["status"] == "failed"


PLUGIN_MODULE = """
from cistrack.api import hookimpl


@hookimpl
def cistrack_step_predicted(run, step):
    raise RuntimeError("module boom")
"""


def test_a_plugin_module_failing_in_a_step_hook_is_named_by_its_distribution_and_entry_point(tmp_path):
    from plugin_site import registry_with_module  # tests/ is on sys.path

    reg = registry_with_module(tmp_path, "boom_plugin", PLUGIN_MODULE, "hplug", "hooks")
    res = run_scenario(_small(), seed=1, registry=reg)
    assert res.summary.failure == "hplug:hooks: cistrack_step_predicted raised RuntimeError: module boom"


class WritesBelief:
    """An observer writing zeros into the means of the belief it is handed."""

    @hookimpl
    def cistrack_step_updated(self, run, step):
        step.belief.mixture.means[:] = 0.0


def test_an_observer_writing_into_the_belief_fails_the_run_naming_it_and_the_hook():
    res = run_scenario(_small(), seed=1, observers=[WritesBelief()])
    assert res.summary.status == "failed"
    assert res.summary.failure.endswith("-WritesBelief: cistrack_step_updated raised ValueError: assignment destination "
                                        "is read-only (what a hook is given is read-only: observers must not modify "
                                        "the step, its belief or the run)")


class TriesEveryWrite:
    """An observer trying to change each array of the belief it is handed, keeping what refused."""

    def __init__(self):
        self.refused: set[str] = set()
        self.tried = 0

    @hookimpl
    def cistrack_step_predicted(self, run, step):
        b = step.belief
        arrays = {"weights": b.mixture.weights, "means": b.mixture.means, "covariances": b.mixture.covariances,
                  "states": b.samples.states}
        for name, a in arrays.items():
            self.tried += 1
            try:
                a *= 1.0
            except ValueError:
                self.refused.add(name)


def test_every_array_of_the_belief_handed_to_observers_refuses_writes_and_the_run_is_unchanged():
    watcher = TriesEveryWrite()
    res = run_scenario(_small(), seed=1, observers=[watcher])
    assert watcher.tried and watcher.refused == {"weights", "means", "covariances", "states"}
    plain = run_scenario(_small(), seed=1)
    assert [r["pos_err_km"] for r in res.rows] == [r["pos_err_km"] for r in plain.rows]


class ExitsWhenFinished:
    """An observer whose cistrack_run_finished calls a library that calls sys.exit."""

    @hookimpl
    def cistrack_run_finished(self, run, summary):
        raise SystemExit(4)


def test_an_observer_calling_sys_exit_at_the_end_fails_the_run_naming_it_and_the_manifest_is_completed(tmp_path):
    res = run_scenario(_small(), seed=1, observers=[ExitsWhenFinished()], output_dir=tmp_path / "run")
    assert res.summary.status == "failed"
    assert res.summary.failure.endswith("-ExitsWhenFinished: SystemExit: it called sys.exit(4)")
    assert json.loads((tmp_path / "run" / "manifest.json").read_text())["status"] == "failed"


def test_an_observer_raising_keyboard_interrupt_itself_is_named_not_reported_as_a_ctrl_c(tmp_path):
    """It had been recorded as 'interrupted (SIGINT, Ctrl-C)', as if someone had pressed Ctrl-C."""
    with pytest.raises(KeyboardInterrupt):
        run_scenario(_small(), seed=1, observers=[ObserverRaises(KeyboardInterrupt("stop"))],
                     output_dir=tmp_path / "run")
    manifest = json.loads((tmp_path / "run" / "manifest.json").read_text())
    assert manifest["status"] == "interrupted"
    assert re.fullmatch(r"interrupted \(KeyboardInterrupt: stop raised in observer-\d-ObserverRaises: "
                        r"cistrack_step_updated\)", manifest["summary"]["failure"])
