"""The ``cistrack`` executable: BLAS libraries loaded with one thread, the collector paused while
its modules load, then the command.

Every run does its linear algebra with one BLAS thread (``blas_threads``, default 1, of
:func:`cistrack.runs.pipeline.run_scenario`: many small matrices), and a least-squares fit's
matrices are as small. A BLAS library loaded with more threads still costs CPU: OpenBLAS starts
its thread pool when it loads and its threads spin for about 0.1 s of CPU before they sleep, once
for numpy's OpenBLAS and once for scipy's, so about 0.13 s of a 1.9 s ``cistrack run example-1``
process went to threads that never did any work (``benchmarks/process_timeline.py``: importing
numpy 0.113 s CPU against 0.060 s wall, numba's target context, which imports scipy.linalg, 0.384
s against 0.282 s). So before anything imports numpy this module sets ``$OPENBLAS_NUM_THREADS``,
``$MKL_NUM_THREADS`` and ``$BLIS_NUM_THREADS`` to 1 where they are unset; a variable the user set
is left as it is. Worker processes of a study inherit them. Importing :mod:`cistrack.cli` from
Python changes nothing in the process's environment: only the executable does this.

The cyclic garbage collector is paused while the command's modules load, and the objects they
made are then frozen (:func:`gc.freeze`) before it resumes: module-level objects live as long as
the process, yet every full collection walked them again. In a ``cistrack run example-1`` process
the collector's passes took 0.084 s (``gc.callbacks``: about 290 collections, one full one of
0.041 s early in the run), 0.046 s with this. The whole process's CPU time fell by about 1 %
(new/old 0.978-1.007 over three alternated runs of 15-25 pairs): within this shared machine's
spread, the system time rising a little where the user time fell. The command itself runs with
the collector on; a frozen object is never collected, which for the modules' own objects changes
nothing.
"""
from __future__ import annotations

import gc
import os
import sys

__all__ = ["BLAS_THREAD_VARIABLES", "console_main"]

BLAS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS")
"""The variables a BLAS library reads for its thread count when it loads."""


def console_main() -> None:
    """The ``cistrack`` command (:func:`cistrack.cli.main.console_main`), its BLAS libraries
    loaded with one thread unless the environment says otherwise."""
    for name in BLAS_THREAD_VARIABLES:
        if not os.environ.get(name, "").strip():
            os.environ[name] = "1"
    gc.disable()
    try:
        from cistrack.cli.main import console_main as command
    except KeyboardInterrupt:  # Ctrl-C while the command is still loading (before its handlers exist)
        sys.stderr.write("cistrack: interrupted (SIGINT) while starting; nothing was done\n")
        raise SystemExit(130) from None
    finally:
        gc.freeze()
        gc.enable()
    command()
