"""The ``cistrack`` executable loads its BLAS libraries with one thread (cistrack.console): every
run's linear algebra uses one BLAS thread anyway, and a thread pool started at load spins CPU
for nothing. A thread count the user set is kept, and importing cistrack from Python leaves the
environment alone."""
from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from importlib import metadata

from cistrack.cli.main import main
from cistrack.console import BLAS_THREAD_VARIABLES

#: a child process: the executable's entry point runs a command, then (at exit) numpy and scipy's
#: linear algebra load and the thread counts of the BLAS libraries and $OPENBLAS_NUM_THREADS are printed
CHILD = textwrap.dedent("""
    import atexit, os, sys

    def report():
        import numpy, scipy.linalg
        from threadpoolctl import threadpool_info
        print("BLAS", sorted({lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"}),
              os.environ["OPENBLAS_NUM_THREADS"])

    atexit.register(report)
    sys.argv = ["cistrack", "scenarios"]
    from cistrack.console import console_main
    console_main()
    """)


def _blas_threads_in_a_cistrack_process(env_extra: dict[str, str]) -> str:
    env = {k: v for k, v in os.environ.items() if k not in BLAS_THREAD_VARIABLES + ("OMP_NUM_THREADS",)}
    proc = subprocess.run([sys.executable, "-c", CHILD], capture_output=True, text=True, timeout=300,
                          env={**env, **env_extra})
    assert proc.returncode == 0, proc.stderr
    return proc.stdout.strip().splitlines()[-1]


def test_the_installed_command_is_the_console_entry_point():
    (script,) = [ep for ep in metadata.entry_points(group="console_scripts") if ep.name == "cistrack"]
    assert script.value == "cistrack.console:console_main"


def test_a_cistrack_process_loads_blas_with_one_thread():
    assert _blas_threads_in_a_cistrack_process({}) == "BLAS [1] 1"


def test_a_thread_count_the_user_set_is_kept():
    assert _blas_threads_in_a_cistrack_process({"OPENBLAS_NUM_THREADS": "2"}).endswith(" 2")


def test_the_command_called_from_python_leaves_the_environment_alone(monkeypatch, capsys):
    for name in BLAS_THREAD_VARIABLES:
        monkeypatch.delenv(name, raising=False)
    assert main(["scenarios"]) == 0
    assert not any(name in os.environ for name in BLAS_THREAD_VARIABLES)
