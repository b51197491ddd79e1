"""The shipped real-data example fitted into a fresh folder, for the tests of what reads a fit back
(predict, its interrupts); tests/ is on sys.path."""
from __future__ import annotations

from pathlib import Path


def fitted_example(tmp_path_factory) -> Path:
    """The results folder of ``cistrack fit`` on the shipped real-data example (its orbit hits the
    Moon on 2026-03-17 at 00:56 UTC)."""
    from cistrack.fitting.from_observations import fit_files
    from cistrack.scenario.builtin_scenarios import builtin_scenario_path

    obs = builtin_scenario_path("real-data").parent / "real_data" / "observations.psv"
    out = tmp_path_factory.mktemp("fit") / "fit"
    [one] = fit_files([obs], out=out)
    assert one.ok
    return out
