"""The ``cistrack`` executable pauses the garbage collector while its modules load and freezes
what they made (cistrack.console): the command then runs with the collector on, and full
collections no longer walk the modules' own objects."""
from __future__ import annotations

import gc
import subprocess
import sys
import textwrap

from cistrack.cli.main import main

#: a child process: the executable's entry point runs a command; at exit the collector's state is printed
CHILD = textwrap.dedent("""
    import atexit, gc, sys

    atexit.register(lambda: print("COLLECTOR", gc.isenabled(), gc.get_freeze_count() > 1000))
    sys.argv = ["cistrack", "scenarios"]
    from cistrack.console import console_main
    console_main()
    """)


def test_a_cistrack_command_runs_with_the_collector_on_and_its_modules_frozen():
    proc = subprocess.run([sys.executable, "-c", CHILD], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip().splitlines()[-1] == "COLLECTOR True True"


def test_the_command_called_from_python_leaves_the_collector_alone(capsys):
    frozen = gc.get_freeze_count()
    assert main(["scenarios"]) == 0
    assert gc.isenabled() and gc.get_freeze_count() == frozen
