"""How the command line shows a Python warning: one ``cistrack: warning:`` line, not Python's
source file, line number and source line."""
from __future__ import annotations

import subprocess
import sys


def test_a_warning_is_one_cistrack_line_without_a_source_location(capsys):
    from cistrack.cli.main import show_warning

    show_warning(RuntimeWarning("cistrack: recording r.rrd stopped at step 3"), RuntimeWarning,
                 "/site-packages/cistrack/plugins/recorders/rerun_recorder.py", 451)
    assert capsys.readouterr().err == "cistrack: warning: recording r.rrd stopped at step 3\n"


def test_the_command_shows_warnings_that_way():
    code = ("import sys, warnings\n"
            "import importlib; m = importlib.import_module('cistrack.cli.main')\n"
            "sys.argv = ['cistrack', 'scenarios']\n"
            "m.main = lambda: warnings.warn('cistrack: something to know', RuntimeWarning) or 0\n"
            "m.console_main()\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stderr == "cistrack: warning: something to know\n"
