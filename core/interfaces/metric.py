"""The interface of a step metric: one stage of the metrics a run computes at every step.

A run's metric stage (:mod:`cistrack.evaluation.metric_stage`) calls every :class:`StepMetric` in
the order their ``needs`` declare and merges what each returns into ``step.metrics`` before any
observer sees the step. A plugin adds stages through the ``cistrack_metric_stages(scenario)`` hook.
"""
from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping
from typing import Any

__all__ = ["StepMetric", "EVENTS"]

EVENTS: tuple[str, ...] = ("predicted", "updated")
"""The step events a metric is computed for (named as the lifecycle hooks that follow them; see
:func:`cistrack.results.step_table.is_table_step` for the events that are rows of the table)."""


class StepMetric(ABC):
    """One stage of a step's metrics.

    Attributes
    ----------
    name : str              unique among a run's stages, e.g. "custody"
    needs : tuple of str    names of the stages whose metrics ``compute`` reads from ``step.metrics``;
                            they run before this one
    """

    name: str = ""
    needs: tuple[str, ...] = ()

    def start(self, run: Any) -> None:
        """Called once per run, before the first step; ``run`` is the
        :class:`cistrack.runs.run_context.RunContext`. Nothing by default."""

    @abstractmethod
    def compute(self, run: Any, step: Any, event: str) -> Mapping[str, float]:
        """The metrics this stage adds to ``step`` (a :class:`cistrack.runs.run_context.Step`) at
        ``event`` (one of :data:`EVENTS`): metric name -> float in the table's units (km, m/s,
        cm/s, nats, arcsec), or an empty dict. ``step.metrics`` holds what the earlier stages
        computed (read-only)."""
