"""The per-step results table: one function builds a step's row, one observer collects rows.

:func:`step_row` is the only place a row is built, and :func:`row_of` builds it once per step:
the results writer (``steps.parquet``), the in-memory :attr:`cistrack.runs.pipeline.RunResult.rows`
and the run summary all hold the same dict.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from cistrack import units
from cistrack.plugin.hookspecs import hookimpl
from cistrack.interfaces.filter import diagnostic_column

__all__ = ["step_row", "row_of", "RowCollector"]


def step_row(run, step) -> dict[str, Any]:
    """The results-table row of one step: identifiers, time (TU, days, UTC), the measurement
    index (-1 for none), metrics (km, m/s, cm/s, nats), numeric diagnostics as ``diag_*`` and
    stage timings as ``time_*_s`` (wall seconds: ``time_predict_s`` the prediction and forming the
    predicted belief, the PGM's clustering included; ``time_update_s`` the update and forming the
    posterior; ``time_metrics_s`` every metric stage of the step; ``time_initialize_s`` on the first row)."""
    row: dict[str, Any] = {
        "run_id": run.run_id, "seed": int(run.seed), "step": int(step.index), "kind": step.kind,
        "t_tu": float(step.t), "t_days": float(units.tu_to_days(step.t)), "utc": step.utc,
        "measurement_index": int(step.measurement.index) if step.measurement is not None else -1,
    }
    for k, v in step.metrics.items():
        row[k] = float(v)
    for k, v in step.diagnostics.items():
        if isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool):
            row[diagnostic_column(k)] = float(v)
    for k, v in step.timings.items():
        row[f"time_{k}_s"] = float(v)
    return row


def row_of(run, step) -> dict[str, Any]:
    """The step's row, built on the first call and kept on the step: every observer that writes
    rows (the in-memory collector, the results writer) hands on the same dict. A step's row is
    asked for only once its metrics, diagnostics and timings are final (in the step hooks, which
    follow the run's metric stage)."""
    if step.row is None:
        step.row = step_row(run, step)
    return step.row


def is_table_step(hook: str, step) -> bool:
    """Whether the event ``hook`` ("predicted" or "updated") of ``step`` is a row of the table:
    every update (posterior), the initial cloud and prediction-only steps (not the prior of an update)."""
    return hook == "updated" or step.kind in ("predict", "initial")


class RowCollector:
    """Observer that keeps every table row of a run in memory (``rows``) and, optionally, the
    steps themselves (``steps``). The run's metric stage has completed each step's metrics
    before any observer sees it (:mod:`cistrack.evaluation.metric_stage`), so no hook order is needed."""

    def __init__(self, keep_steps: bool = False) -> None:
        self.rows: list[dict[str, Any]] = []
        self.steps: list = []
        self.keep_steps = keep_steps

    def _add(self, run, step) -> None:
        self.rows.append(row_of(run, step))
        if self.keep_steps:
            self.steps.append(step)

    @hookimpl
    def cistrack_step_predicted(self, run, step) -> None:
        if is_table_step("predicted", step):
            self._add(run, step)

    @hookimpl
    def cistrack_step_updated(self, run, step) -> None:
        self._add(run, step)
