"""The observers and metric stages of one run: the observers a run always has, the plugin manager
that calls their lifecycle hooks, the run's metric stage (built-in stages and the plugins'), and
the end of the run, where each observer's ``cistrack_run_finished`` is called on its own."""
from __future__ import annotations

import dataclasses
from typing import Any, Iterable

import pluggy

from cistrack.errors import ConfigError
from cistrack.evaluation.custody import CustodyMetric
from cistrack.evaluation.information_bound import InformationBoundMetric
from cistrack.evaluation.metric_stage import MetricStage, StepMetric
from cistrack.evaluation.metrics import BeliefMetric, PassIndexMetric
from cistrack.evaluation.residuals import ResidualMetric
from cistrack.evaluation.run_summary import RunSummary
from cistrack.plugin import hookspecs
from cistrack.plugin.registry import Registry
from cistrack.runs.run_context import RunContext, RunOptions
from cistrack.scenario.limits import check_count

__all__ = ["make_plugin_manager", "finish_observers", "run_observers", "builtin_metrics", "metric_stage",
           "checked_observers"]

_LIFECYCLE = ("cistrack_run_started", "cistrack_step_predicted", "cistrack_step_updated",
              "cistrack_run_failed", "cistrack_run_finished", "cistrack_metric_stages")


def run_observers(first: list[Any], options: RunOptions, registry: Registry) -> list[Any]:
    """The observers of a run, in registration order: ``first`` (the run's own: custody, the row
    collector), with ``options.output_dir`` the results and estimates writers, then
    ``options.observers``."""
    obs = list(first)
    if options.output_dir is not None:
        from cistrack.results.estimates import EstimateWriter
        from cistrack.results.part_files import ROWS_PER_PART
        from cistrack.results.store import ResultsWriter

        n = (ROWS_PER_PART if options.rows_per_part is None
             else check_count(options.rows_per_part, "rows_per_part (--rows-per-part)", 1, 10 ** 9))
        obs += [ResultsWriter(options.output_dir, registry, rows_per_part=n),
                EstimateWriter(options.output_dir, rows_per_part=n)]
    return obs + checked_observers(options.observers, "observers")


def checked_observers(observers: Iterable[Any] | None, argument: str = "observers") -> list[Any]:
    """``observers`` as a list, each implementing at least one cistrack hook (a method marked
    ``@cistrack.hookimpl`` named after a lifecycle hook or ``cistrack_metric_stages``); a
    ConfigError names ``argument``, the index and what an observer is otherwise."""
    allowed = ", ".join(_LIFECYCLE)
    if observers is None:
        return []
    if isinstance(observers, (str, bytes)) or not isinstance(observers, Iterable):
        raise ConfigError(f"{argument}: must be a list of observers (objects with @cistrack.hookimpl methods "
                          f"named {allowed}), got {type(observers).__name__}")
    out = list(observers)
    probe = pluggy.PluginManager(hookspecs.PROJECT)
    for i, obs in enumerate(out):
        if not any(probe.parse_hookimpl_opts(obs, h) is not None for h in _LIFECYCLE):
            raise ConfigError(f"{argument}[{i}]: {type(obs).__name__} object implements no cistrack hook; an "
                              f"observer is an object with one or more methods marked @cistrack.hookimpl named "
                              f"{allowed} (docs/plugins.md)")
    return out


def builtin_metrics(custody: CustodyMetric) -> list[StepMetric]:
    """The built-in metric stages of every run, in their order, with the run's ``custody`` stage:
    the belief against the truth, the pass index, the information bound, the residuals, custody."""
    return [BeliefMetric(), PassIndexMetric(), InformationBoundMetric(), ResidualMetric(), custody]


def metric_stage(pm: pluggy.PluginManager, scenario: Any, builtins: list[StepMetric]) -> MetricStage:
    """The run's :class:`MetricStage`: ``builtins``, then the stages that plugins and observers return
    from ``cistrack_metric_stages`` (in registration order), each after the stages it needs.
    Raises ConfigError when a stage needs one that is missing, or names repeat."""
    found = pm.hook.cistrack_metric_stages(scenario=scenario)  # pluggy's call order: last registered first
    return MetricStage([*builtins, *(s for stages in reversed(found) for s in (stages or ()))])


def make_plugin_manager(observers: Iterable[Any], registry: Registry) -> pluggy.PluginManager:
    """A plugin manager for one run: the given observers plus installed plugins that implement
    lifecycle hooks or ``cistrack_metric_stages`` (third-party observers and metrics declared
    under the ``cistrack`` entry points)."""
    pm = pluggy.PluginManager(hookspecs.PROJECT)
    pm.add_hookspecs(hookspecs.CistrackSpecs)
    for dist, ep, module in registry.plugins:
        if any(hasattr(module, h) for h in _LIFECYCLE):
            pm.register(module, name=f"{dist}:{ep}")
    for i, obs in enumerate(observers):
        pm.register(obs, name=f"observer-{i}-{type(obs).__name__}")
    return pm


def finish_observers(pm: pluggy.PluginManager, ctx: RunContext, summary: RunSummary) -> RunSummary:
    """Call every observer's ``cistrack_run_finished``, each on its own and in pluggy's order
    (results writers declare ``trylast``, so they come last), so that one failing observer (a
    recorder, a full disk) never keeps the completed steps from being merged; an observer's
    failure turns a finished run into "failed" with the reason, and every later observer is handed
    that summary."""
    errors: list[str] = []
    told = 0  # errors already in the summary
    for impl in reversed(pm.hook.cistrack_run_finished.get_hookimpls()):  # pluggy's call order
        if len(errors) > told:
            summary = dataclasses.replace(
                summary, status="failed" if summary.status == "finished" else summary.status,
                failure="; ".join(([summary.failure] if summary.failure else []) + errors[told:]))
            told = len(errors)
        try:
            args = {"run": ctx, "summary": summary}
            impl.function(*[args[a] for a in impl.argnames])
        except Exception as exc:
            errors.append(f"{impl.plugin_name}: {type(exc).__name__}: {exc}")
    if len(errors) > told:  # the last observers failed: say so in the summary returned
        summary = dataclasses.replace(
            summary, status="failed" if summary.status == "finished" else summary.status,
            failure="; ".join(([summary.failure] if summary.failure else []) + errors[told:]))
    return summary
