"""The worker threads that run compiled kernels on disjoint ranges of rows (GIL released).

Shared by the ensemble propagation (:mod:`cistrack.propagation`) and the compiled mixture
densities (:mod:`cistrack.model.mixture_density`). Each row's numbers are computed by the same operations
whichever thread runs it, so the thread count never changes a result.
"""
from __future__ import annotations

import os
import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from cistrack.errors import ConfigError

__all__ = ["num_threads", "run_chunks"]

_POOL: ThreadPoolExecutor | None = None
_POOL_PID = -1


def num_threads() -> int:
    """Worker threads: ``$CISTRACK_NUM_THREADS``, else numba's thread count
    (``$NUMBA_NUM_THREADS``, default: the CPUs this process may use). The thread count never
    changes the numbers (rows are computed independently).

    Raises :class:`ConfigError` if ``$CISTRACK_NUM_THREADS`` is not an integer from 1 to 1024."""
    env = os.environ.get("CISTRACK_NUM_THREADS")
    if env is not None and env.strip():
        digits = env.strip()
        n = int(digits) if digits.isascii() and digits.isdigit() else 0  # int() would take "1_0" as 10
        if not 1 <= n <= 1024:
            raise ConfigError(f"environment variable CISTRACK_NUM_THREADS={env!r}: must be an integer "
                              "from 1 to 1024 (or unset: numba's thread count)")
        return n
    import numba

    return max(1, int(numba.config.NUMBA_NUM_THREADS))


def _pool(workers: int) -> ThreadPoolExecutor:
    global _POOL, _POOL_PID
    if _POOL is None or _POOL_PID != os.getpid() or _POOL._max_workers != workers:
        _POOL = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="cistrack-propagate")
        _POOL_PID = os.getpid()
    return _POOL


def run_chunks(kernel, n: int, args: tuple, chunks_per_worker: int = 8) -> None:
    """Run ``kernel(i0, i1, *args)`` over 0..n in chunks on the calling thread and the worker
    threads (GIL released).

    ``chunks_per_worker``: several chunks per worker balance uneven rows (particles near a close
    approach take more steps); rows of equal cost need one. The chunks are taken in turn by
    whichever thread is free, the calling thread among them: it starts at once, where a sleeping
    worker takes time to wake (on a virtual machine's idle core, as long as a short call itself)."""
    workers = min(num_threads(), n)
    if workers <= 1 or n < 32:
        kernel(0, n, *args)
        return
    if not getattr(kernel, "signatures", True):  # numba dispatcher not loaded yet: load it here on an
        kernel(0, 0, *args)                       # empty range, or each worker thread would load it
    n_chunks = min(n, workers * chunks_per_worker)
    edges = np.linspace(0, n, n_chunks + 1).astype(np.int64)
    chunks = iter([(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:]) if b > a])
    lock = threading.Lock()

    def drain() -> None:
        while True:
            with lock:
                chunk = next(chunks, None)
            if chunk is None:
                return
            try:
                kernel(chunk[0], chunk[1], *args)
            except BaseException:  # (Ctrl-C included) no thread takes a further chunk
                with lock:
                    for _ in chunks:
                        pass
                raise

    helpers = [_pool(workers - 1).submit(drain) for _ in range(workers - 1)]
    try:
        drain()
    finally:  # the helpers finish (or fail) before the caller's arrays are handed back
        for fut in helpers:
            fut.result()
