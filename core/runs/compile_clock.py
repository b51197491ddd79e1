"""Seconds numba spends compiling, so a run's wall time can be given without them.

The first run of a model on a new machine compiles its propagation kernels (about a minute);
later runs load them from the on-disk cache. :class:`CompileClock` listens to numba's
``numba:compile`` events (fired only when code is really compiled, not on a cache hit) while it
is active, from any thread, and adds up their durations.
"""
from __future__ import annotations

import threading
import time
from typing import Any

__all__ = ["CompileClock"]


class CompileClock:
    """Context manager: ``seconds`` is the time spent compiling while it was active (nested and
    overlapping compilations counted once)."""

    def __init__(self) -> None:
        self.seconds = 0.0
        self._depth = 0
        self._t0 = 0.0
        self._lock = threading.Lock()
        self._listener: Any = None

    def _start(self, event: Any) -> None:
        with self._lock:
            if self._depth == 0:
                self._t0 = time.perf_counter()
            self._depth += 1

    def _end(self, event: Any) -> None:
        with self._lock:
            self._depth -= 1
            if self._depth == 0:
                self.seconds += time.perf_counter() - self._t0

    def __enter__(self) -> "CompileClock":
        from numba.core import event

        clock = self

        class _Listener(event.Listener):
            def on_start(self, ev: Any) -> None:
                clock._start(ev)

            def on_end(self, ev: Any) -> None:
                clock._end(ev)

        self._listener = _Listener()
        event.register("numba:compile", self._listener)
        return self

    def __exit__(self, *exc: Any) -> None:
        from numba.core import event

        event.unregister("numba:compile", self._listener)
