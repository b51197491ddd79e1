"""The worker threads that run compiled kernels on disjoint ranges of rows (GIL released), and
the thread limit of the OpenMP and BLAS libraries during a run.

Shared by the ensemble propagation (:mod:`cistrack.propagation`) and the compiled mixture
densities (:mod:`cistrack.model.mixture_density`). Each row's numbers are computed by the same operations
whichever thread runs it, so the thread count never changes a result.

:func:`library_thread_limit` keeps the OpenMP and BLAS thread pools of every loaded library
(numpy's and scipy's BLAS, scikit-learn's OpenMP, a plugin's own) to :func:`num_threads` inside
a run, so ``$CISTRACK_NUM_THREADS`` bounds plugins too.
"""
from __future__ import annotations

import os
import threading
import time
from collections.abc import Iterable, Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from typing import Any

import numpy as np

from cistrack.errors import ConfigError

__all__ = ["num_threads", "thread_setting", "run_chunks", "library_thread_limit", "capped_threads", "SHARE_MIN_SECONDS"]

_POOL: ThreadPoolExecutor | None = None
_POOL_PID = -1


def num_threads() -> int:
    """Worker threads: ``$CISTRACK_NUM_THREADS``, else numba's thread count
    (``$NUMBA_NUM_THREADS``, default: the CPUs this process may use). The thread count never
    changes the numbers (rows are computed independently).

    Raises :class:`ConfigError` if ``$CISTRACK_NUM_THREADS`` is not an integer from 1 to 1024."""
    n = thread_setting()
    if n is not None:
        return n
    _check_numba_threads()
    import numba

    return max(1, int(numba.config.NUMBA_NUM_THREADS))


def _whole_number(text: str) -> int:
    """``text`` as a whole number of ASCII digits, else 0 (int() would take "1_0" as 10, or "１")."""
    digits = text.strip()
    return int(digits) if digits.isascii() and digits.isdigit() else 0


def _check_numba_threads() -> None:
    """ConfigError naming ``$NUMBA_NUM_THREADS`` when it is set but not a whole number of at least 1
    (numba itself raises a bare ValueError from deep inside its import)."""
    env = os.environ.get("NUMBA_NUM_THREADS")
    if env is None or not env.strip():
        return
    if _whole_number(env) < 1:
        raise ConfigError(f"environment variable NUMBA_NUM_THREADS={env!r}: must be a whole number of threads, at "
                          "least 1 (or unset: the CPUs this process may use)")


def thread_setting() -> int | None:
    """``$CISTRACK_NUM_THREADS`` as a count, None when unset or blank (numba is not imported).

    Raises :class:`ConfigError` if it is not an integer from 1 to 1024."""
    env = os.environ.get("CISTRACK_NUM_THREADS")
    if env is None or not env.strip():
        return None
    n = _whole_number(env)
    if not 1 <= n <= 1024:
        raise ConfigError(f"environment variable CISTRACK_NUM_THREADS={env!r}: must be an integer "
                          "from 1 to 1024 (or unset: numba's thread count)")
    return n


def _pool(workers: int) -> ThreadPoolExecutor:
    global _POOL, _POOL_PID
    if _POOL is None or _POOL_PID != os.getpid() or _POOL._max_workers != workers:
        _POOL = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="cistrack-propagate")
        _POOL_PID = os.getpid()
    return _POOL


SHARE_MIN_SECONDS = 0.004
"""Work that the calling thread alone would finish within this many seconds (estimated from its
first chunk) is not shared: waking a worker and handing chunks back and forth cost more CPU than
the wall time it saves there (Example 1's propagations, about 0.6 ms at 10,000 particles, took the
same wall time on one thread as on two, with 0.1 s more CPU per run: docs/performance.md)."""

_PROBE_CHUNKS = 4
"""Chunks per worker at least, so that the first chunk, which the calling thread runs alone to
estimate the work, is a small share of it."""


def run_chunks(kernel, n: int, args: tuple, chunks_per_worker: int = 8) -> None:
    """Run ``kernel(i0, i1, *args)`` over 0..n in chunks on the calling thread and, when the work
    is large enough (:data:`SHARE_MIN_SECONDS`), the worker threads (GIL released).

    ``chunks_per_worker``: several chunks per worker balance uneven rows (particles near a close
    approach take more steps); rows of equal cost need few. The calling thread runs the first
    chunk and times it; if the rest would take it less than :data:`SHARE_MIN_SECONDS` it runs the
    rest too. Otherwise the chunks are taken in turn by whichever thread is free, the calling
    thread among them: it goes on at once, where a sleeping worker takes time to wake (on a
    virtual machine's idle core, as long as a short call itself)."""
    workers = min(num_threads(), n)
    if workers <= 1 or n < 32:
        kernel(0, n, *args)
        return
    if not getattr(kernel, "signatures", True):  # numba dispatcher not loaded yet: load it here on an
        kernel(0, 0, *args)                       # empty range, or each worker thread would load it
    n_chunks = min(n, workers * max(chunks_per_worker, _PROBE_CHUNKS))
    edges = np.linspace(0, n, n_chunks + 1).astype(np.int64)
    chunks = iter([(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:]) if b > a])
    i0, i1 = next(chunks)
    started = time.perf_counter()
    kernel(i0, i1, *args)
    if (time.perf_counter() - started) * (n - i1) / (i1 - i0) < SHARE_MIN_SECONDS:
        for i0, i1 in chunks:
            kernel(i0, i1, *args)
        return
    _share(kernel, chunks, args, workers)


def _share(kernel, chunks: Iterator[tuple[int, int]], args: tuple, workers: int) -> None:
    """Run the remaining ``chunks`` on the calling thread and ``workers - 1`` worker threads."""
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


#: the variables an OpenMP or BLAS library reads when it loads: its thread count from then on
_THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS")
_API_VARIABLE = {"openmp": "OMP_NUM_THREADS", "openblas": "OPENBLAS_NUM_THREADS", "mkl": "MKL_NUM_THREADS",
                 "blis": "BLIS_NUM_THREADS"}


def _env_int(name: str, env: dict[str, str | None]) -> int | None:
    """The first integer of ``$name`` ("4" or "4,2"), None when unset or not a positive integer."""
    text = (env.get(name) or "").split(",")[0].strip()
    return int(text) if text.isascii() and text.isdigit() and int(text) > 0 else None


@contextmanager
def capped_threads(libraries: Iterable[Any], caps: dict[str, int]) -> Iterator[None]:
    """Lower each threadpoolctl library controller in ``libraries`` to ``caps[user_api]`` threads
    ("openmp", "blas") inside the block, then give each back its own count. A library already
    at or below its cap is left alone: a tighter limit set around the block holds."""
    lowered = []
    try:
        for lib in libraries:
            cap = caps.get(lib.user_api)
            count = lib.num_threads
            if cap is not None and count > cap:
                lib.set_num_threads(cap)
                lowered.append((lib, count))
        yield
    finally:
        for lib, count in reversed(lowered):
            lib.set_num_threads(count)


@contextmanager
def library_thread_limit(n: int | None = None, *, blas: int | None = None) -> Iterator[int]:
    """Keep OpenMP libraries to ``n`` threads and BLAS libraries to ``min(blas, n)`` inside the
    block (``n`` default :func:`num_threads`; ``blas`` None: ``n``); yields ``n``.

    Libraries already loaded are lowered through threadpoolctl (never raised). One first loaded
    inside the block (a plugin importing scikit-learn at its first call) reads the limit from
    ``$OMP_NUM_THREADS`` and friends, set for the block only, and is given back its usual count
    at the end. OpenMP's limit holds on the calling thread and the threads it starts.

    Raises :class:`ConfigError` for a bad ``$CISTRACK_NUM_THREADS``."""
    from threadpoolctl import ThreadpoolController

    n = num_threads() if n is None else n
    caps = {"openmp": n, "blas": n if blas is None else max(1, min(blas, n))}
    saved = {k: os.environ.get(k) for k in _THREAD_VARIABLES}
    loaded = ThreadpoolController().lib_controllers
    before = {lib.filepath for lib in loaded}
    try:
        for key in _THREAD_VARIABLES:
            cap = caps["openmp" if key == "OMP_NUM_THREADS" else "blas"]
            if (_env_int(key, saved) or cap + 1) > cap:
                os.environ[key] = str(cap)
        with capped_threads(loaded, caps):
            yield n
    finally:
        for key, value in saved.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value
        _give_back_late_libraries(before, saved)


def _give_back_late_libraries(before: set[str], env: dict[str, str | None]) -> None:
    """Libraries loaded inside :func:`library_thread_limit` get the thread count they would have
    had without it: their own variable, else ``$OMP_NUM_THREADS``, else the usable CPUs."""
    from threadpoolctl import ThreadpoolController

    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    for lib in ThreadpoolController().lib_controllers:
        if lib.filepath not in before:
            own = _API_VARIABLE.get(lib.internal_api, "OMP_NUM_THREADS")
            lib.set_num_threads(_env_int(own, env) or _env_int("OMP_NUM_THREADS", env) or cpus)
