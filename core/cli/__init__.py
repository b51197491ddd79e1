"""The ``cistrack`` command: argument parsing and commands (:mod:`.main`), study commands,
signal handling and process exit codes.

The top layer of the framework: it may import every other package.
``cistrack.cli`` was one module before 0.2; ``console_main`` and ``main`` are still importable from here.
"""
import sys as _sys

try:
    from cistrack.cli.main import console_main, main
except KeyboardInterrupt:  # Ctrl-C while the command is still loading (before its handlers exist)
    if _sys.argv[:1] != ["-m"]:  # imported from Python: the caller's interrupt, as it came
        raise
    from cistrack.interrupts import exit_interrupted_while_starting

    exit_interrupted_while_starting()

__all__ = ["console_main", "main"]
