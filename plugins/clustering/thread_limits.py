"""Running scikit-learn's OpenMP and BLAS loops on a bounded number of threads.

scikit-learn's k-means uses every core through OpenMP. On a machine whose other cores are
busy (parallel studies, other runs) OpenMP's spinning threads make a 20 ms k-means take
400 ms; the filters call the clusterer at every measurement, so they run it single-threaded
by default and parallelise across runs instead. A clusterer's ``n_threads`` never goes above
the run's thread limit (:func:`cistrack.threads.num_threads`, ``$CISTRACK_NUM_THREADS``).
"""
from __future__ import annotations

from contextlib import contextmanager

from cistrack.threads import capped_threads, num_threads

__all__ = ["limited_threads"]

_CONTROLLER = None


@contextmanager
def limited_threads(n_threads: int):
    """Limit OpenMP and BLAS threads to ``n_threads`` inside the block (0 = the run's limit),
    never above :func:`cistrack.threads.num_threads` nor above a limit set around the block."""
    global _CONTROLLER
    n = min(n_threads, num_threads()) if n_threads > 0 else num_threads()
    if _CONTROLLER is None:
        from threadpoolctl import ThreadpoolController
        _CONTROLLER = ThreadpoolController()  # after scikit-learn's import: its OpenMP is in it
    with capped_threads(_CONTROLLER.lib_controllers, {"openmp": n, "blas": n}):
        yield
