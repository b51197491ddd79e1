"""Running scikit-learn's OpenMP and BLAS loops on a bounded number of threads.

scikit-learn's k-means uses every core through OpenMP. On a machine whose other cores are
busy (parallel studies, other runs) OpenMP's spinning threads make a 20 ms k-means take
400 ms; the filters call the clusterer at every measurement, so they run it single-threaded
by default and parallelise across runs instead.
"""
from __future__ import annotations

from contextlib import contextmanager

__all__ = ["limited_threads"]

_CONTROLLER = None


@contextmanager
def limited_threads(n_threads: int):
    """Limit OpenMP and BLAS threads to ``n_threads`` inside the block (0 = no limit)."""
    global _CONTROLLER
    if n_threads <= 0:
        yield
        return
    if _CONTROLLER is None:
        from threadpoolctl import ThreadpoolController
        _CONTROLLER = ThreadpoolController()
    with _CONTROLLER.limit(limits=n_threads):
        yield
