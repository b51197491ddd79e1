"""Fast ensemble propagation for any model given as a numba-jitted right-hand side.

A model subclasses :class:`CompiledDynamics`, names its equations of motion in the class
attribute ``rhs`` and returns its constants from :meth:`CompiledDynamics.params_vector`; it
then inherits :meth:`~CompiledDynamics.propagate` (per-particle adaptive DOP853 8(5,3), all
cores, output at many times, forward or backward, impacts on :attr:`bodies`) and
:meth:`~CompiledDynamics.derivatives`.

Writing a new model in your own package (say a bicircular four-body problem)::

    # mypkg/bcr4bp.py
    import numpy as np
    from numba import njit
    from cistrack.component import check_positive
    from cistrack.hookspecs import hookimpl
    from cistrack.plugins.dynamics.compiled import CompiledDynamics

    @njit(cache=True, fastmath={"contract", "arcp", "nsz", "reassoc"})
    def bcr4bp_rhs(t, y, p, out):          # y, out: (6,) float64; p: params_vector()
        mu, ms, a_s, om_s = p[0], p[1], p[2], p[3]
        ...                                # write out[0..5]; no allocation, no Python objects
    class BCR4BP(CompiledDynamics):
        rhs = bcr4bp_rhs                   # a module-level njit function (so it can be cached)
        def __init__(self, mu: float = 1.2150582e-2, rtol: float = 1e-11, atol: float = 1e-12):
            self.mu = mu; self.rtol = rtol; self.atol = atol   # validate with check_* here
        def params_vector(self):
            return np.array([self.mu, 328900.54, 388.81, -0.925195985])

    @hookimpl
    def cistrack_register(registry):
        registry.add("dynamics", "bcr4bp", BCR4BP)

and declare ``bcr4bp = "mypkg.bcr4bp"`` under ``[project.entry-points.cistrack]``. The right-hand
side must be a module-level ``@njit`` function ``rhs(t, y, params, out)`` on float64 arrays.
Bodies (impact surfaces) come from overriding :attr:`bodies`.

How the speed is obtained: for each right-hand side, :mod:`.integrator_dop853` writes a module
with the integrator unrolled around that function, stored in the kernel cache directory
(``$CISTRACK_KERNEL_DIR``, else ``$XDG_CACHE_HOME/cistrack/kernels``, else
``~/.cache/cistrack/kernels``) under a name hashed from the integrator, the model's source file
and numba's version; numba compiles it once (``cache=True``) and later processes load the
machine code from disk. A right-hand side that is not importable by module and name (defined in
``__main__`` or inside a function) still works, compiled in memory on every new process.
"""
from __future__ import annotations

import hashlib
import importlib.util
import inspect
import os
import sys
import tempfile
import threading
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from types import ModuleType
from typing import Any, ClassVar

import numba
import numpy as np

from cistrack.errors import PropagationError, StateError
from cistrack.interfaces.dynamics import Body, Dynamics, Propagation

from . import integrator_dop853

__all__ = ["CompiledDynamics", "PropagationError", "StateError", "kernels_for", "kernel_cache_dir",
           "num_threads"]


# -- kernel generation and caching ----------------------------------------------------------------

_LOCK = threading.Lock()
_KERNELS: dict[tuple[int, int], ModuleType] = {}


def kernel_cache_dir() -> Path:
    """Directory where generated kernel modules (and numba's cache of them) are kept."""
    env = os.environ.get("CISTRACK_KERNEL_DIR")
    if env:
        return Path(env)
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg) if xdg else Path.home() / ".cache"
    return base / "cistrack" / "kernels"


def _importable_name(rhs: Any) -> tuple[str, str] | None:
    """(module, name) if ``rhs`` can be imported back as ``from module import name``."""
    func = getattr(rhs, "py_func", None)
    if func is None:
        return None
    mod, name = func.__module__, func.__qualname__
    if mod in (None, "__main__") or "<" in name or "." in name:
        return None
    module = sys.modules.get(mod)
    if module is None or getattr(module, name, None) is not rhs:
        return None
    return mod, name


def _source_digest(rhs: Any) -> str:
    """Hash of the file defining ``rhs`` (so editing the model invalidates its kernel)."""
    try:
        text = Path(inspect.getsourcefile(rhs.py_func)).read_bytes()
    except (TypeError, OSError):
        text = repr(rhs).encode()
    return hashlib.sha256(text).hexdigest()


def _load_file_module(name: str, path: Path) -> ModuleType:
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def _write_atomic(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".tmp-", suffix=".py")
    with os.fdopen(fd, "w") as fh:
        fh.write(text)
    os.replace(tmp, path)


def kernels_for(rhs: Any, dim: int = 6) -> ModuleType:
    """The generated module (``propagate_kernel``, ``derivatives_kernel``) for ``rhs``.

    Built once per process and right-hand side; on disk once per model source and numba version.
    """
    key = (id(rhs), int(dim))
    with _LOCK:
        mod = _KERNELS.get(key)
        if mod is not None:
            return mod
        where = _importable_name(rhs)
        if where is not None:
            src = integrator_dop853.generate_source(
                f"from {where[0]} import {where[1]} as rhs", dim, title=f"for {where[0]}.{where[1]}")
            digest = hashlib.sha256(
                (src + _source_digest(rhs) + numba.__version__ + sys.version).encode()).hexdigest()[:20]
            name = f"cistrack_kernel_{where[1]}_{digest}"
            mod = None
            for directory in (kernel_cache_dir(), Path(tempfile.gettempdir()) / "cistrack-kernels"):
                path = directory / f"{name}.py"
                try:
                    if not path.exists() or path.read_text() != src:
                        _write_atomic(path, src)
                    mod = _load_file_module(name, path)
                    break
                except OSError:
                    continue
        if where is None or mod is None:  # not importable or no writable directory: in memory
            src = integrator_dop853.generate_source("", dim, cache=False, title="(in memory)")
            mod = ModuleType(f"cistrack_kernel_inmemory_{id(rhs)}")
            mod.__dict__["rhs"] = rhs  # the generated header re-wraps it for inlining
            exec(compile(src, f"<cistrack kernel for {rhs!r}>", "exec"), mod.__dict__)
        _KERNELS[key] = mod
        return mod


# -- threads ---------------------------------------------------------------------------------------

_POOL: ThreadPoolExecutor | None = None
_POOL_PID = -1


def num_threads() -> int:
    """Worker threads used by propagate: ``$CISTRACK_NUM_THREADS``, else numba's thread count
    (``$NUMBA_NUM_THREADS``, default: the CPUs this process may use)."""
    env = os.environ.get("CISTRACK_NUM_THREADS")
    if env:
        try:
            return max(1, int(env))
        except ValueError:
            pass
    return max(1, int(numba.config.NUMBA_NUM_THREADS))


def _pool(workers: int) -> ThreadPoolExecutor:
    global _POOL, _POOL_PID
    if _POOL is None or _POOL_PID != os.getpid() or _POOL._max_workers != workers:
        _POOL = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="cistrack-propagate")
        _POOL_PID = os.getpid()
    return _POOL


def _run_chunks(kernel, n: int, args: tuple) -> None:
    """Run ``kernel(i0, i1, *args)`` over 0..n in chunks on the worker threads (GIL released)."""
    workers = min(num_threads(), n)
    if workers <= 1 or n < 32:
        kernel(0, n, *args)
        return
    # several chunks per worker so that uneven particles (close approaches) balance out
    n_chunks = min(n, workers * 8)
    edges = np.linspace(0, n, n_chunks + 1).astype(np.int64)
    futures = [_pool(workers).submit(kernel, int(a), int(b), *args)
               for a, b in zip(edges[:-1], edges[1:]) if b > a]
    for fut in futures:
        fut.result()


# -- the base class ------------------------------------------------------------------------------

class CompiledDynamics(Dynamics):
    """Base class of models given by a numba right-hand side; see the module docstring.

    Subclasses set the class attribute ``rhs`` (an ``@njit`` function ``rhs(t, y, params, out)``
    on float64 arrays, ``y``/``out`` of length ``dim``), implement :meth:`params_vector`, and have
    the instance attributes ``rtol`` and ``atol`` (per-particle relative and absolute error
    tolerances of the integrator, nondimensional). ``max_steps`` (per particle and call) may be
    overridden.
    """

    rhs: ClassVar[Any] = None
    dim: ClassVar[int] = 6
    max_steps: int = 5_000_000

    def params_vector(self) -> np.ndarray:
        """Model constants handed to ``rhs`` as ``params``, (P,) float64."""
        return np.zeros(1)

    # -- helpers ----------------------------------------------------------------------------------
    def _kernels(self) -> ModuleType:
        rhs = type(self).rhs
        if rhs is None or not hasattr(rhs, "py_func"):
            raise TypeError(f"{type(self).__name__}.rhs must be a numba @njit function")
        return kernels_for(rhs, self.dim)

    def _params(self) -> np.ndarray:
        return np.ascontiguousarray(self.params_vector(), dtype=np.float64).reshape(-1)

    def _bodies_arrays(self) -> tuple[np.ndarray, np.ndarray]:
        bodies = self.bodies
        pos = np.zeros((max(len(bodies), 1), 3))
        rad = np.zeros(len(bodies))
        for i, b in enumerate(bodies):
            pos[i] = np.asarray(b.position, dtype=float)
            rad[i] = float(b.radius)
        return pos, rad

    def _check_states(self, states: Any) -> np.ndarray:
        try:
            arr = np.asarray(states, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise StateError(f"{self._label()}: states must be a numeric (N, {self.dim}) array: {exc}") from None
        if arr.ndim == 1:
            arr = arr.reshape(1, -1)
        if arr.ndim != 2 or arr.shape[1] != self.dim:
            raise StateError(f"{self._label()}: states must have shape (N, {self.dim}), got {np.shape(states)}")
        if not np.all(np.isfinite(arr)):
            bad = int(np.sum(~np.all(np.isfinite(arr), axis=1)))
            raise StateError(f"{self._label()}: {bad} state(s) contain NaN or inf")
        return np.ascontiguousarray(arr)

    # -- Dynamics ---------------------------------------------------------------------------------
    def derivatives(self, t: float, states: np.ndarray) -> np.ndarray:
        """Time derivative of ``states`` (N, dim) [LU, VU] at ``t`` (TU) -> (N, dim) [VU, VU/TU]."""
        arr = self._check_states(states)
        out = np.empty_like(arr)
        self._kernels().derivatives_kernel(float(t), arr, self._params(), out)
        return out

    def propagate(self, states: np.ndarray, t0: float, times: Any, *,
                  rtol: float | None = None, atol: float | None = None) -> Propagation:
        """Propagate ``states`` (N, dim) from ``t0`` to each of ``times`` (scalar or (K,), TU).

        Every particle is integrated with its own adaptive step and error control (DOP853,
        tolerances ``rtol``/``atol``, default the model's). ``times`` must all lie on one side of
        ``t0`` and be monotonic away from it (backward propagation: all earlier). Returns a
        :class:`~cistrack.interfaces.dynamics.Propagation` with ``states`` (K, N, dim); particles
        that hit a body are frozen at the located impact point with ``alive`` False.

        Raises :class:`StateError` for malformed input and :class:`PropagationError` if a particle
        exhausts ``max_steps`` or its step size underflows.
        """
        arr = self._check_states(states)
        t0 = float(t0)
        t_out = np.atleast_1d(np.asarray(times, dtype=np.float64)).reshape(-1)
        if t_out.size == 0:
            raise StateError(f"{self._label()}: no output times given")
        if not (np.isfinite(t0) and np.all(np.isfinite(t_out))):
            raise StateError(f"{self._label()}: t0 and times must be finite")
        d = np.diff(np.concatenate(([t0], t_out)))
        if not (np.all(d >= 0) or np.all(d <= 0)):
            raise StateError(f"{self._label()}: times must be monotonic in one direction from t0={t0}")
        rtol = float(self.rtol if rtol is None else rtol)
        atol = float(self.atol if atol is None else atol)
        n = arr.shape[0]
        out = np.empty((t_out.size, n, self.dim))
        impact_body = np.full(n, -1, dtype=np.int64)
        impact_time = np.full(n, np.inf)
        status = np.zeros(n, dtype=np.int64)
        pos, rad = self._bodies_arrays()
        if n:
            _run_chunks(self._kernels().propagate_kernel, n,
                        (arr, self._params(), t0, np.ascontiguousarray(t_out), rtol, atol, pos, rad,
                         int(self.max_steps), 0.0, out, impact_body, impact_time, status))
        failed = status >= 2
        if np.any(failed):
            limit = int(np.sum(status == 2))
            under = int(np.sum(status == 3))
            raise PropagationError(
                f"{self._label()}: {int(failed.sum())} of {n} particle(s) did not reach t={t_out[-1]:g} TU "
                f"({limit} hit the step limit max_steps={self.max_steps}, {under} had step-size underflow)")
        return Propagation(times=t_out, states=out, alive=impact_body < 0,
                           impact_body=impact_body, impact_time=impact_time)
