"""The observers and metric stages of one run: the observers a run always has, the plugin manager
that calls their lifecycle hooks, the run's metric stage (built-in stages and the plugins'), and
the end of the run, where each observer's ``cistrack_run_finished`` is called on its own."""
from __future__ import annotations

import dataclasses
from typing import Any, Iterable

import pluggy

from cistrack.errors import ConfigError, PluginError, RunInterrupted, exception_text
from cistrack.interrupts import interrupt_text, plugin_fault
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
           "checked_observers", "notify", "interrupted_late"]

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
    Raises ConfigError naming the plugin when its hook raises or returns anything but a list of
    StepMetric objects (or None), and when a stage needs one that is missing, or names repeat."""
    stages, origins = list(builtins), {}
    for impl in pm.hook.cistrack_metric_stages.get_hookimpls():  # registration order (pluggy calls the last first)
        for s in _stages_of(impl, scenario):
            stages.append(s)
            origins.setdefault(s.name, impl.plugin_name)
    return MetricStage(stages, origins)


def _stages_of(impl: Any, scenario: Any) -> list[StepMetric]:
    """The stages one ``cistrack_metric_stages`` implementation returns, checked."""
    who = f"{impl.plugin_name}: cistrack_metric_stages"
    try:
        found = impl.function(*[{"scenario": scenario}[a] for a in impl.argnames])
    except BaseException as exc:  # GeneratorExit, a KeyboardInterrupt no signal raised too (probe I1)
        if not plugin_fault(exc):
            raise
        raise ConfigError(f"{who} raised {exception_text(exc)}") from exc
    if found is None:
        return []
    if not isinstance(found, (list, tuple)):
        raise ConfigError(f"{who} must return a list of cistrack.api.StepMetric objects (or None), got "
                          f"{type(found).__name__} {_short(found)}")
    for s in found:
        if not isinstance(s, StepMetric):
            raise ConfigError(f"{who} returned {type(s).__name__} {_short(s)}, which is not a cistrack.api.StepMetric")
    return list(found)


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def notify(pm: pluggy.PluginManager, hook: str, **kwargs: Any) -> None:
    """Call every implementation of the lifecycle ``hook`` with ``kwargs``, in pluggy's order (the
    last registered first). One that raises, or calls ``sys.exit``, stops the run with a
    :class:`~cistrack.errors.PluginError` naming its plugin and the hook. A KeyboardInterrupt
    passes, the run ends "interrupted"; one that is not a signal's (:class:`RunInterrupted`, which
    the command's handlers raise) says where it was raised, as the hook may have raised it itself
    (it had been reported as "interrupted (SIGINT, Ctrl-C)")."""
    for impl in reversed(getattr(pm.hook, hook).get_hookimpls()):
        try:
            impl.function(*[kwargs[a] for a in impl.argnames])
        except RunInterrupted:
            raise
        except BaseException as exc:  # GeneratorExit, a KeyboardInterrupt no signal raised too (probe I1)
            if not plugin_fault(exc):  # without a message it may be Python's own Ctrl-C (no handlers: the API)
                what = exception_text(exc) if str(exc) else "a Ctrl-C (SIGINT) or a KeyboardInterrupt"
                raise KeyboardInterrupt(f"{what} raised in {impl.plugin_name}: {hook}") from exc
            raise PluginError(f"{impl.plugin_name}: {hook} raised {exception_text(exc)}{_read_only_hint(exc)}") from exc


def _read_only_hint(exc: BaseException) -> str:
    """What to do instead, when ``exc`` is numpy's refusal to write into a read-only array."""
    if isinstance(exc, ValueError) and "read-only" in str(exc):
        return " (what a hook is given is read-only: observers must not modify the step, its belief or the run)"
    return ""


def make_plugin_manager(observers: Iterable[Any], registry: Registry) -> pluggy.PluginManager:
    """A plugin manager for one run: the given observers plus installed plugins that implement
    lifecycle hooks or ``cistrack_metric_stages`` (third-party observers and metrics declared
    under the ``cistrack`` entry points)."""
    pm = pluggy.PluginManager(hookspecs.PROJECT)
    pm.add_hookspecs(hookspecs.CistrackSpecs)
    for dist, ep, module in registry.plugins:
        if _lifecycle_hooks(module):
            pm.register(module, name=f"{dist}:{ep}")
    for i, obs in enumerate(observers):
        pm.register(obs, name=f"observer-{i}-{type(obs).__name__}")
    return pm


def _lifecycle_hooks(module: Any) -> list[str]:
    """The lifecycle hooks (or ``cistrack_metric_stages``) ``module`` implements: by a function's
    name, or by a ``@hookimpl(specname=...)`` under another name, which had left such a plugin
    unregistered and its hook never called (probe M11)."""
    marker = f"{hookspecs.PROJECT}_impl"
    found = [h for h in _LIFECYCLE if hasattr(module, h)]
    for name in dir(module):
        opts = getattr(getattr(module, name, None), marker, None)
        spec = opts.get("specname") if isinstance(opts, dict) else None
        if spec in _LIFECYCLE and spec not in found:
            found.append(spec)
    return found


def finish_observers(pm: pluggy.PluginManager, ctx: RunContext, summary: RunSummary) -> RunSummary:
    """Call every observer's ``cistrack_run_finished``, each on its own and in pluggy's order
    (results writers declare ``trylast``, so they come last), so that one failing observer (a
    recorder, a full disk) never keeps the completed steps from being merged; an observer's
    failure turns a finished run into "failed" with the reason, and every later observer is handed
    that summary. An interrupt (Ctrl-C, SIGTERM) in one makes the run "interrupted"
    (:func:`interrupted_late`) for the observers after it (the results writer comes last, and
    records it in the manifest), and is raised again once they have all been called."""
    errors: list[str] = []
    told, interrupt = 0, None  # errors already in the summary; the first interrupt
    for impl in reversed(pm.hook.cistrack_run_finished.get_hookimpls()):  # pluggy's call order
        if len(errors) > told:
            summary = dataclasses.replace(
                summary, status="failed" if summary.status == "finished" else summary.status,
                failure="; ".join(([summary.failure] if summary.failure else []) + errors[told:]))
            told = len(errors)
        try:
            args = {"run": ctx, "summary": summary}
            impl.function(*[args[a] for a in impl.argnames])
        except BaseException as exc:  # sys.exit, GeneratorExit in a plugin: its failure, not the process's end
            if plugin_fault(exc):
                errors.append(f"{impl.plugin_name}: {exception_text(exc)}")
            else:
                interrupt, summary = interrupt or exc, interrupted_late(summary, exc)
    if len(errors) > told:  # the last observers failed: say so in the summary returned
        summary = dataclasses.replace(
            summary, status="failed" if summary.status == "finished" else summary.status,
            failure="; ".join(([summary.failure] if summary.failure else []) + errors[told:]))
    if interrupt is not None:
        raise interrupt
    return summary


def interrupted_late(summary: RunSummary, exc: BaseException) -> RunSummary:
    """``summary`` of a run interrupted (``exc``) after its last step, while its burns were
    estimated or its observers finished: status "interrupted", the interrupt added to its failure
    (``interrupted (SIGINT, Ctrl-C) after the last step``), the verdict judged at its end kept. As it
    is when it already says "interrupted"."""
    if summary.status == "interrupted":
        return summary
    text = f"{interrupt_text(exc)} after the last step"
    return dataclasses.replace(summary, status="interrupted", failure="; ".join(filter(None, (summary.failure, text))))
