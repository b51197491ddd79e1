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


def _in_a_frame_named(code_name: str, filename: str, handler):
    """Call the signal ``handler`` (SIGINT) from a frame with that function and file name."""
    import signal as _signal

    ns: dict = {}
    src = f"def {code_name}(h, s):\n    import sys\n    return h(s, sys._getframe())\n"
    exec(compile(src, filename, "exec"), ns)
    return ns[code_name](handler, _signal.SIGINT)


def test_a_ctrl_c_in_importlibs_module_lock_callback_is_kept_for_later_not_raised_there():
    """There Python prints the exception as "ignored" with its traceback and drops it (a Ctrl-C
    during a lazy import did so under a run's progress bar); it is noted, and raised between the
    run's steps."""
    from cistrack.cli.signals import _raise_ctrl_c

    clear()
    _in_a_frame_named("cb", "<frozen importlib._bootstrap>", _raise_ctrl_c)
    with pytest.raises(RunInterrupted):
        raise_pending()


def test_a_ctrl_c_anywhere_else_is_raised_where_it_arrives():
    from cistrack.cli.signals import _raise_ctrl_c

    clear()
    with pytest.raises(RunInterrupted):
        _in_a_frame_named("cb", "mine.py", _raise_ctrl_c)
    clear()
