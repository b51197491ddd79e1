"""The observers of one run: the plugin manager that calls their lifecycle hooks, and the end of
the run, where each observer's ``cistrack_run_finished`` is called on its own."""
from __future__ import annotations

import dataclasses
from typing import Any, Iterable

import pluggy

from cistrack.evaluation.run_summary import RunSummary
from cistrack.plugin import hookspecs
from cistrack.plugin.registry import Registry
from cistrack.runs.run_context import RunContext

__all__ = ["make_plugin_manager", "finish_observers"]

_LIFECYCLE = ("cistrack_run_started", "cistrack_step_predicted", "cistrack_step_updated",
              "cistrack_run_failed", "cistrack_run_finished")


def make_plugin_manager(observers: Iterable[Any], registry: Registry) -> pluggy.PluginManager:
    """A plugin manager for one run: the given observers plus installed plugins that implement
    lifecycle hooks (third-party observers declared under the ``cistrack`` entry points)."""
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
