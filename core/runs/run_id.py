"""The one place a run's id is made: ``SCENARIO__FILTER__IOD__seedN``.

It names the run's results folder, its rows in study reports and its recording; the CLI, the
pipeline and studies all build it here.
"""
from __future__ import annotations

from typing import Any

__all__ = ["run_id", "scenario_run_id"]


def run_id(scenario: str, filter_label: str, iod_label: str, seed: int) -> str:
    """``run_id("example-1", "pgm", "noisy-range", 3) == "example-1__pgm__noisy-range__seed3"``.

    ``filter_label`` and ``iod_label`` are the component names, or a study's labels for them."""
    return f"{scenario}__{filter_label}__{iod_label}__seed{seed}"


def scenario_run_id(scenario: Any, seed: int) -> str:
    """The id of one run of a validated :class:`~cistrack.scenario.loading.Scenario` with ``seed``."""
    return run_id(scenario.name, scenario.components["filter"].name, scenario.components["iod"].name, seed)
