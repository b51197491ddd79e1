"""Compiling a model's lockstep propagation kernel in a second process while this one works.

On the first run on a machine (empty kernel cache) numba compiles what a run needs one function
after the other, under its process-wide compiler lock: the truth's dense-output kernel, then the
filter's SIMD-lockstep kernel (their costs: :data:`COMPILE_CPU_SECONDS`).
With a second core, :func:`start` launches ``python -m cistrack.propagation.background_compile``,
which builds the same generated kernel module and propagates ``LANES`` copies of one state for a
moment, so that numba compiles the lockstep kernel there and writes it to its on-disk cache;
meanwhile this process compiles the dense kernel and runs the truth and the IOD.
:meth:`CompiledDynamics.propagate` calls :func:`wait_for` before it uses a lockstep kernel:
it waits for the child, and numba then loads the kernel from the cache (the same machine code:
the cache gives bit-identical results, see :mod:`.kernels`). Nothing else changes: if the child
cannot start or fails, this process compiles the kernel itself, as before.
"""
from __future__ import annotations

import atexit
import logging
import os
import pickle
import subprocess
import sys
import time
from typing import Any

import numpy as np

__all__ = ["start", "wait_for", "lockstep_cached", "lockstep_available", "idle_core", "COMPILE_CPU_SECONDS", "estimate_seconds"]

_LOG = logging.getLogger("cistrack.propagation")

COMPILE_CPU_SECONDS = {"dense_kernel": 5.9, "propagate_lanes_kernel": 7.1, "propagate_kernel": 1.2,
                       "process start": 1.5}
"""CPU seconds of compiling each kernel of the CR3BP (and of starting the compiling process),
measured with numba's ``numba:compile`` events on the 2-core AMD EPYC development machine
(numba 0.68; the lockstep kernel after the dense one, which compiles the helpers both use; the
lockstep kernel scaled by 0.87 for its inlined stages, measured alone)."""

_CHILDREN: dict[str, subprocess.Popen] = {}


def _cpus() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


def idle_core() -> bool:
    """Whether a second process would find a core free: at least 2 usable CPUs and a 1-minute
    load average below their number (on busy cores the two processes share them and compile
    the helpers both kernels use twice, which costs more than it saves).
    ``CISTRACK_BACKGROUND_COMPILE=0`` (no, false, off) says no, ``=1`` (yes, true, on) yes whatever
    the load (:func:`cistrack.env_flags.env_flag`)."""
    from cistrack.env_flags import env_flag

    forced = env_flag("CISTRACK_BACKGROUND_COMPILE")
    if forced is not None:
        return forced
    try:
        load = os.getloadavg()[0]
    except OSError:
        load = 0.0
    return _cpus() >= 2 and load < _cpus()


def estimate_seconds(kernels: tuple[str, ...], parallel: bool) -> float:
    """Rough wall seconds to compile ``kernels`` (names of :data:`COMPILE_CPU_SECONDS`), the
    lockstep one in a second process when ``parallel``, scaled up when the machine is busy
    (load average above its free cores)."""
    cpu = [COMPILE_CPU_SECONDS[k] for k in kernels]
    if parallel and "propagate_lanes_kernel" in kernels:
        rest = sum(c for k, c in zip(kernels, cpu) if k != "propagate_lanes_kernel")
        seconds = max(rest, COMPILE_CPU_SECONDS["propagate_lanes_kernel"] + COMPILE_CPU_SECONDS["process start"])
    else:
        seconds = sum(cpu)
    try:
        load = os.getloadavg()[0]
    except OSError:
        load = 0.0
    return seconds * max(1.0, (load + (2 if parallel else 1)) / _cpus())


def lockstep_cached(mod: Any) -> bool:
    """Whether the lockstep kernel of generated module ``mod`` is compiled in this process or in
    numba's on-disk cache (True when the module has none: nothing to compile)."""
    kernel = getattr(mod, "propagate_lanes_kernel", None)
    if kernel is None or kernel.signatures:
        return True
    try:  # numba's index file for the function (numba.core.caching; absent: never compiled)
        return os.path.exists(kernel._cache._cache_file._index_path)
    except AttributeError:
        return True


def lockstep_available(mod: Any) -> bool:
    """Whether the lockstep kernel of generated module ``mod`` needs no compiling here: compiled
    in this process, in numba's on-disk cache, or being compiled by a child (:func:`start`)."""
    return mod.__name__ in _CHILDREN or lockstep_cached(mod)


def start(dynamics: Any, state: np.ndarray) -> bool:
    """Start compiling the lockstep kernel of ``dynamics`` (a :class:`CompiledDynamics`) in a
    child process, propagating copies of ``state`` (dim,) for a moment. Returns whether a child
    was started (not when the kernel is cached, no core is idle (:func:`idle_core`), or the
    model cannot be handed to another process)."""
    mod = dynamics._kernels()
    if lockstep_cached(mod) or mod.__name__ in _CHILDREN or not idle_core():
        return False
    try:
        payload = pickle.dumps((dynamics, np.asarray(state, dtype=np.float64).reshape(-1)))
    except Exception as exc:  # a model that cannot be pickled compiles here, as before
        _LOG.debug("no background compilation for %r: %s", dynamics, exc)
        return False
    try:
        child = subprocess.Popen([sys.executable, "-m", "cistrack.propagation.background_compile"],
                                 stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        child.stdin.write(payload)
        child.stdin.close()
    except OSError as exc:
        _LOG.debug("no background compilation: %s", exc)
        return False
    _CHILDREN[mod.__name__] = child
    return True


def wait_for(mod: Any) -> None:
    """Wait for a child compiling the lockstep kernel of ``mod``, if one was started."""
    child = _CHILDREN.pop(getattr(mod, "__name__", ""), None)
    if child is None:
        return
    t = time.perf_counter()
    err = child.stderr.read()
    child.wait()
    child.stderr.close()
    if child.returncode != 0:
        _LOG.debug("background compilation failed (%s): %s", child.returncode, err.decode(errors="replace")[-500:])
    elif time.perf_counter() - t > 1.0:
        _LOG.debug("waited %.1f s for the background compilation", time.perf_counter() - t)


@atexit.register
def _stop_children() -> None:
    for child in _CHILDREN.values():
        if child.poll() is None:
            child.terminate()
    _CHILDREN.clear()


def _main() -> int:
    dynamics, state = pickle.load(sys.stdin.buffer)
    mod = dynamics._kernels()
    states = np.repeat(state[None], mod.LANES, axis=0)
    dynamics.propagate(states, 0.0, 1e-3)
    return 0 if mod.propagate_lanes_kernel.signatures else 1


if __name__ == "__main__":
    sys.exit(_main())
