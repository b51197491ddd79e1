"""The cistrack hook specifications (pluggy project name ``"cistrack"``).

A plugin is a module (or object) with functions decorated by :data:`hookimpl`, named after
the specs below, declared under the entry-point group ``cistrack`` in its package's
``pyproject.toml``::

    [project.entry-points.cistrack]
    my-filter = "my_package.my_filter"

Registration hook
-----------------
``cistrack_register(registry)`` is called once per plugin when the registry loads; the plugin
adds its components with ``registry.add(kind, name, factory)``.

Lifecycle hooks
---------------
Observers (result writers, the rerun recorder, progress displays, your own) receive the
events of a run. They are called in the process that runs the scenario, in order, and must not
modify the objects they are given.
"""
from __future__ import annotations

import pluggy

PROJECT = "cistrack"
hookspec = pluggy.HookspecMarker(PROJECT)
hookimpl = pluggy.HookimplMarker(PROJECT)


class CistrackSpecs:
    """Hook specifications. Each argument is passed by keyword."""

    @hookspec
    def cistrack_register(self, registry):
        """Add components to ``registry`` (a :class:`cistrack.plugin.registry.Registry` view bound to
        this plugin's distribution) with ``registry.add(kind, name, factory)``."""

    @hookspec
    def cistrack_run_started(self, run):
        """A run has its truth, measurements and IOD cloud; ``run`` is a
        :class:`cistrack.runs.pipeline.RunContext` (scenario, seed, truth, measurements, components).
        Called after IOD, before the first filter step."""

    @hookspec
    def cistrack_step_predicted(self, run, step):
        """The filter predicted to a measurement time; ``step`` is a :class:`cistrack.runs.pipeline.Step`
        whose ``belief`` is the prior."""

    @hookspec
    def cistrack_step_updated(self, run, step):
        """The filter used the measurement; ``step.belief`` is the posterior and
        ``step.metrics`` the step's metrics."""

    @hookspec
    def cistrack_run_failed(self, run, step_index, error):
        """The filter raised at step ``step_index`` (``error``: "ExceptionType: message"); the run
        stops and :func:`cistrack_run_finished` follows with status "filter-failed"."""

    @hookspec
    def cistrack_run_finished(self, run, summary):
        """The run ended; ``summary`` is a :class:`cistrack.evaluation.run_summary.RunSummary` (status,
        custody verdict, final sigmas and errors, timings; ``summary.to_dict()`` for JSON)."""
