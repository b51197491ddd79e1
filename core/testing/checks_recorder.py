"""Conformance checks for recorders: objects whose methods implement lifecycle hooks."""
from __future__ import annotations

import pluggy

from cistrack.plugin import hookspecs
from cistrack.testing.check_support import describe_exception, require

__all__ = ["RECORDER_CHECKS", "lifecycle_hooks"]

LIFECYCLE = ("cistrack_run_started", "cistrack_step_predicted", "cistrack_step_updated", "cistrack_run_failed",
             "cistrack_run_finished")


def lifecycle_hooks(obj) -> list[str]:
    """Names of the lifecycle hooks ``obj`` implements (marked with ``cistrack.hookimpl``)."""
    marker = f"{hookspecs.PROJECT}_impl"
    return [n for n in dir(obj) if n.startswith("cistrack_") and hasattr(getattr(obj, n, None), marker)]


def check_implements_lifecycle_hooks(recorder) -> None:
    """At least one lifecycle hook, each marked @hookimpl, with arguments the spec knows."""
    hooks = lifecycle_hooks(recorder)
    require(hooks, f"no method marked @cistrack.hookimpl among {', '.join(LIFECYCLE)}")
    unknown = [h for h in hooks if h not in LIFECYCLE and h != "cistrack_register"]
    require(not unknown, f"hook implementations with no specification: {unknown} (misspelt?)")
    pm = pluggy.PluginManager(hookspecs.PROJECT)
    pm.add_hookspecs(hookspecs.CistrackSpecs)
    try:
        pm.register(recorder)
        pm.check_pending()
    except Exception as exc:
        require(False, f"pluggy rejected the hook implementations: {describe_exception(exc)}")


RECORDER_CHECKS = [
    ("implements_lifecycle_hooks", check_implements_lifecycle_hooks),
]
