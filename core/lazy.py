"""Numba functions compiled on first call, so that ``import cistrack`` does not import numba.

Importing numba costs about a quarter of a second, and the command line (``cistrack --help``,
``cistrack plugins``) never runs a compiled function. :func:`lazy_njit` takes the options of
:func:`numba.njit` and returns a :class:`LazyJit`: calling it from Python compiles (or loads
numba's on-disk cache) on the first call and then calls the compiled function; a first call that
finds nothing in numba's cache says it is compiling (logging, shown by the command line). Compiled code
cannot call a ``LazyJit`` itself; it calls :attr:`LazyJit.dispatcher`, the numba function.
"""
from __future__ import annotations

import contextlib
import functools
import logging
import os
import pickle
import sys
import threading
from typing import Any, Callable

__all__ = ["LazyJit", "LazyModule", "lazy_njit", "tolerate_damaged_cache"]

_DAMAGE = (pickle.UnpicklingError, EOFError, ValueError, TypeError, AttributeError, IndexError, KeyError,
           ImportError, MemoryError, OverflowError, SystemError)
"""What unpickling a truncated or garbled numba cache file raises (random bytes cut short gave a
MemoryError: a length field read as gigabytes)."""
_TOLERANT = threading.Lock()


_DAMAGE_SAID = threading.Event()


def _say_damage(message: str, *args: Any) -> None:
    """The first damaged cache entry of a process as a warning (saying that later ones are recompiled
    without a word), the rest at debug level: a damaged cache had printed one warning per kernel, 16
    to 18 lines for one run."""
    log = logging.getLogger("cistrack.lazy")
    if _DAMAGE_SAID.is_set():
        log.debug(message, *args)
        return
    _DAMAGE_SAID.set()
    log.warning(message + " (other damaged entries of this cache are compiled again without a word)", *args)


def _damaged_file(exc: BaseException, cache_file: Any) -> str:
    """The file whose unpickling raised ``exc``: the data file (``_load_data``'s ``path``) when that
    is where it failed, else the cache's index."""
    tb = exc.__traceback__
    while tb is not None:
        if tb.tb_frame.f_code.co_name == "_load_data" and tb.tb_frame.f_locals.get("path"):
            return str(tb.tb_frame.f_locals["path"])
        tb = tb.tb_next
    return str(getattr(cache_file, "_index_path", "?"))


@contextlib.contextmanager
def _quiet_buffer_release():
    """While a cache file is unpickled, the interpreter's report of a buffer freed while still
    exported (a garbled pickle's bytearray: CPython prints it through ``sys.excepthook`` itself,
    as a bare "SystemError: deallocated bytearray object has exported buffers" line) is left
    unsaid: the damaged file is named by the warning that follows."""
    before = sys.excepthook

    def hook(kind, value, tb):
        if kind is SystemError and "exported buffers" in str(value):
            logging.getLogger("cistrack.lazy").debug("while reading numba's cache: %s", value)
        else:
            before(kind, value, tb)

    sys.excepthook = hook
    try:
        yield
    finally:
        sys.excepthook = before


def tolerate_damaged_cache() -> None:
    """Make numba treat an unreadable entry of its on-disk cache as absent: the function is compiled
    again (and its entry rewritten), with a warning naming the file (logger ``cistrack.lazy``).

    Numba raises the unpickling error instead, from every later run, until someone finds and
    deletes the file (a disk that filled mid-write, a copied or truncated cache directory). Wraps
    ``numba.core.caching.IndexDataCacheFile.load`` once per process; idempotent."""
    from numba.core import caching

    cls = getattr(caching, "IndexDataCacheFile", None)
    with _TOLERANT:
        load = getattr(cls, "load", None)
        if load is None or getattr(load, "_cistrack_tolerant", False):
            return

        @functools.wraps(load)
        def tolerant_load(self, key):
            try:
                with _quiet_buffer_release():
                    return load(self, key)
            except _DAMAGE as exc:
                _say_damage("numba's cache file %s is damaged (%s: %s); compiling the function again",
                            _damaged_file(exc, self), type(exc).__name__, str(exc)[:80])
                try:
                    self.flush()  # an empty index: the compiled function's entry is written afresh
                except OSError:
                    pass
                return None

        tolerant_load._cistrack_tolerant = True
        cls.load = tolerant_load
        _tolerate_foreign_entries(caching)


def _tolerate_foreign_entries(caching: Any) -> None:
    """Make numba treat a cache entry that unpickles but is not the function's compiled code (a
    well-formed pickle of something else, another function's entry copied over it) as absent, with a
    warning: its rebuild had raised a TypeError traceback, or the run had called another function's
    code ("dense_kernel expected 13 arguments, got 3"). Wraps ``Cache._load_overload`` once."""
    cls = getattr(caching, "Cache", None)
    load = getattr(cls, "_load_overload", None)
    if load is None or getattr(load, "_cistrack_tolerant", False):
        return

    @functools.wraps(load)
    def checked_load(self, sig, target_context):
        try:
            data = load(self, sig, target_context)
        except _DAMAGE as exc:
            return _recompiled(self, f"cannot be rebuilt ({type(exc).__name__}: {str(exc)[:80]})")
        if data is not None and not _compiled_for(data, self, sig):
            return _recompiled(self, "holds another function's compiled code")
        return data

    checked_load._cistrack_tolerant = True
    cls._load_overload = checked_load


def _compiled_for(data: Any, cache: Any, sig: Any) -> bool:
    """Whether the rebuilt ``data`` is the cache's function compiled for ``sig``."""
    from numba.core import sigutils

    try:
        args, _ = sigutils.normalize_signature(sig)
        same_args = tuple(data.signature.args) == tuple(args)
        name = getattr(getattr(data, "fndesc", None), "qualname", None)
        return same_args and (name is None or name == cache._py_func.__qualname__)
    except Exception:  # noqa: BLE001 - anything unreadable in a cache entry is damage
        return False


def _recompiled(cache: Any, why: str) -> None:
    _say_damage("numba's cache entry of %s %s; compiling the function again", getattr(cache, "_name", "?"), why)
    return None


class LazyJit:
    """A Python function and the :func:`numba.njit` options to compile it with on first use."""

    def __init__(self, func: Callable, options: dict[str, Any]):
        self.py_func = func
        self.options = dict(options)
        self._dispatcher = None
        self._announced = False
        self._lock = threading.Lock()
        functools.update_wrapper(self, func)

    @property
    def dispatcher(self):
        """The numba dispatcher (compiled, or loaded from numba's cache, on first access)."""
        if self._dispatcher is None:
            with self._lock:
                if self._dispatcher is None:
                    from numba import njit

                    tolerate_damaged_cache()

                    self._dispatcher = njit(**self.options)(self.py_func)
        return self._dispatcher

    @property
    def targetoptions(self) -> dict[str, Any]:
        """The njit options, as a numba dispatcher exposes them (read by the kernel generator)."""
        return dict(self.options)

    def __call__(self, *args: Any) -> Any:
        if not self._announced:
            self._announced = True
            self._announce_if_uncached()
        return self.dispatcher(*args)

    def _announce_if_uncached(self) -> None:
        """Log (logger ``cistrack.lazy``; the command line shows it) that this first call compiles,
        when numba's on-disk cache holds nothing for the function yet (a fresh install)."""
        if not self.options.get("cache"):
            return
        try:  # numba's index file for this function (numba.core.caching; absent: never compiled here)
            index = self.dispatcher._cache._cache_file._index_path
        except AttributeError:
            return
        if not os.path.exists(index):
            logging.getLogger("cistrack.lazy").info(
                "compiling %s.%s with numba (one-time, a few seconds; later runs load it from numba's cache)...",
                self.py_func.__module__, self.py_func.__qualname__)

    def __repr__(self) -> str:
        return f"LazyJit({self.py_func.__module__}.{self.py_func.__qualname__})"


def lazy_njit(**options: Any) -> Callable[[Callable], LazyJit]:
    """Decorator: ``@lazy_njit(cache=True)`` is ``@numba.njit(cache=True)`` compiled on first call."""
    def wrap(func: Callable) -> LazyJit:
        return LazyJit(func, options)
    return wrap


class LazyModule:
    """A module imported on first attribute access: ``rr = LazyModule("rerun")``.

    For plugin modules that the registry imports to list components: the heavy library is
    loaded when a component first uses it, not when ``cistrack plugins`` runs.
    """

    def __init__(self, name: str):
        self._lazy_name = name

    def __getattr__(self, attr: str) -> Any:
        if attr.startswith("__") and attr.endswith("__"):
            raise AttributeError(attr)
        from importlib import import_module

        return getattr(import_module(self._lazy_name), attr)

    def __repr__(self) -> str:
        return f"LazyModule({self._lazy_name!r})"
