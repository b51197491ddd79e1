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

Metric hook
-----------
``cistrack_metric_stages(scenario)`` returns metric stages
(:class:`cistrack.evaluation.metric_stage.StepMetric`) for a run. Every step's metrics are
computed by the run's stages, in the order their ``needs`` declare, before any observer sees the
step: this is where a step's metrics are made, not in the observers.

Lifecycle hooks
---------------
Observers (result writers, the rerun recorder, progress displays, your own) receive the
events of a run. They are called in the process that runs the scenario, in order, and must not
modify the objects they are given (``step.metrics`` is read-only: changing it raises TypeError;
the arrays of ``step.belief`` are read-only views: writing into them raises ValueError).
No observer depends on another's order.
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
    def cistrack_metric_stages(self, scenario):
        """Return a list of new :class:`cistrack.evaluation.metric_stage.StepMetric` objects to add
        to a run of ``scenario`` (a :class:`cistrack.scenario.loading.Scenario`), or None. Called
        once per run, before the truth and the IOD; the stages run after the built-in ones
        ("belief", "pass_index", "information_bound", "residuals", "custody") unless their
        ``needs`` order them otherwise, and their metrics become columns of ``steps.parquet``."""

    @hookspec
    def cistrack_run_started(self, run):
        """A run has its truth, measurements and IOD cloud; ``run`` is a
        :class:`cistrack.runs.pipeline.RunContext` (scenario, seed, truth, measurements, components).
        Called after IOD, before the first filter step."""

    @hookspec
    def cistrack_step_predicted(self, run, step):
        """The filter predicted to a measurement time; ``step`` is a :class:`cistrack.runs.pipeline.Step`
        whose ``belief`` is the prior and ``step.metrics`` (read-only) what the metric stages
        computed for it (all of a row's metrics for the initial cloud and prediction-only steps)."""

    @hookspec
    def cistrack_step_updated(self, run, step):
        """The filter used the measurement; ``step.belief`` is the posterior and
        ``step.metrics`` (read-only) the step's metrics, complete."""

    @hookspec
    def cistrack_run_failed(self, run, step_index, error):
        """The filter raised at step ``step_index`` (``error``: "ExceptionType: message"); the run
        stops and :func:`cistrack_run_finished` follows with status "filter-failed"."""

    @hookspec
    def cistrack_run_finished(self, run, summary):
        """The run ended; ``summary`` is a :class:`cistrack.evaluation.run_summary.RunSummary` (status,
        custody verdict, final sigmas and errors, timings; ``summary.to_dict()`` for JSON)."""
