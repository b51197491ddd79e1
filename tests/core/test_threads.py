"""The worker threads of cistrack.threads: every row once, the calling thread working too, work too
small to share done on the calling thread alone, and a failing chunk reported after every thread
has stopped."""
from __future__ import annotations

import threading
import time

import numpy as np
import pytest

import cistrack.threads
from cistrack.threads import run_chunks


@pytest.fixture
def threads(monkeypatch):
    def use(n: int) -> None:
        monkeypatch.setenv("CISTRACK_NUM_THREADS", str(n))
    return use


@pytest.mark.parametrize("share_below", [0.0, cistrack.threads.SHARE_MIN_SECONDS])
@pytest.mark.parametrize("n_threads", [1, 2, 3])
@pytest.mark.parametrize("n", [31, 32, 100, 1001])
def test_every_row_is_computed_exactly_once(threads, monkeypatch, n_threads, n, share_below):
    threads(n_threads)
    monkeypatch.setattr(cistrack.threads, "SHARE_MIN_SECONDS", share_below)  # 0: always shared
    hits = np.zeros(n, dtype=np.int64)

    def kernel(i0, i1, out):
        out[i0:i1] += 1

    run_chunks(kernel, n, (hits,))
    assert np.all(hits == 1)


def test_the_calling_thread_takes_chunks_beside_the_workers(threads):
    threads(2)
    seen: list[str] = []

    def kernel(i0, i1):
        seen.append(threading.current_thread().name)
        time.sleep(0.005)  # a chunk long enough that both threads are busy

    run_chunks(kernel, 1000, ())
    assert len(seen) == 16  # 2 threads x 8 chunks each
    assert threading.current_thread().name in seen
    assert any(name.startswith("cistrack-propagate") for name in seen)


def test_work_too_small_to_share_stays_on_the_calling_thread(threads):
    threads(2)
    seen: list[str] = []

    def kernel(i0, i1):
        seen.append(threading.current_thread().name)

    run_chunks(kernel, 1000, ())
    assert len(seen) == 16 and set(seen) == {threading.current_thread().name}


def test_a_failing_chunk_is_raised_once_every_thread_has_stopped(threads):
    threads(2)
    started: list[int] = []

    def kernel(i0, i1):
        started.append(i0)
        time.sleep(0.005)
        if i0 == 0:
            raise FloatingPointError("chunk 0 failed")

    with pytest.raises(FloatingPointError, match="chunk 0 failed"):
        run_chunks(kernel, 1000, ())
    count = len(started)
    time.sleep(0.05)
    assert len(started) == count  # nothing still running after the call returned
    assert count < 16  # the helpers took no further chunk once the caller's failed
