"""A Ctrl-C raised where Python loses it (inside the compiler's ctypes callback, whose exceptions
are printed as "ignored") still stops the run, between its steps: one had finished and exited 0."""
from __future__ import annotations

import json

import pytest

from cistrack.errors import RunInterrupted
from cistrack.interrupts import clear, note, raise_pending
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario
from cistrack.scenario.settings import apply_settings


def test_an_interrupt_noted_but_lost_ends_the_run_as_interrupted(tmp_path):
    scen = apply_settings(load_scenario("quick"), ["filter.n_particles=200", "iod.n_particles=200"])
    note(RunInterrupted())  # what the handler records before raising into a callback that swallows it
    try:
        with pytest.raises(RunInterrupted):
            run_scenario(scen, seed=1, output_dir=tmp_path / "r")
    finally:
        clear()
    manifest = json.loads((tmp_path / "r" / "manifest.json").read_text())
    assert manifest["status"] == "interrupted"


def test_a_pending_interrupt_is_raised_once():
    note(RunInterrupted("SIGTERM"))
    with pytest.raises(RunInterrupted, match="SIGTERM"):
        raise_pending()
    raise_pending()  # nothing left: returns
