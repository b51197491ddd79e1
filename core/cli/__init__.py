"""The ``cistrack`` command: argument parsing and commands (:mod:`.main`), study commands,
signal handling and process exit codes.

The top layer of the framework: it may import every other package.
``cistrack.cli`` was one module before 0.2; ``console_main`` and ``main`` are still importable from here.
"""
from cistrack.cli.main import console_main, main

__all__ = ["console_main", "main"]
