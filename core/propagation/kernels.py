"""Kernel generation, on-disk cache and worker threads of compiled ensemble propagation.

How the speed is obtained: for each right-hand side, :mod:`.dop853_source` writes a module
with the integrator unrolled around that function (and, when :mod:`.lane_rhs` can rewrite the
function into straight-line lane code, the SIMD-lockstep integrator of
:mod:`.dop853_lanes_source`), stored in the kernel cache directory
(``$CISTRACK_KERNEL_DIR``, else ``$XDG_CACHE_HOME/cistrack/kernels``, else
``~/.cache/cistrack/kernels``) under a name hashed from the integrator, the model's source file
and numba's version; numba compiles it once (``cache=True``) and later processes load the
machine code from disk. A right-hand side that is not importable by module and name (defined in
``__main__`` or inside a function) still works, compiled in memory on every new process.

The cache directory holds code that is imported, so it must belong to the user running cistrack:
it is created with mode 0700, and an existing one owned by another user or writable by group or
others is refused (:class:`~cistrack.errors.ConfigError` naming the directory and
``CISTRACK_KERNEL_DIR``). There is no fallback to a shared directory such as ``/tmp``: if the
directory cannot be created or written the kernels are compiled in memory (same numbers, only
slower to start) and a warning says why.

Reproducibility: compiled kernels give bit-identical results whether they were compiled in this
process or loaded from the cache, and for any number of threads (each particle is integrated on
its own, so the split over threads changes nothing). This holds because the generated code uses no
value-changing fast-math flags: see :data:`.dop853_source.DEFAULT_FASTMATH`.

"""
from __future__ import annotations

import errno
import hashlib
import importlib.util
import inspect
import logging
import os
import shlex
import stat
import sys
import tempfile
import threading
import warnings
from pathlib import Path
from types import ModuleType
from typing import Any

from cistrack.errors import ConfigError
from cistrack.threads import num_threads, run_chunks  # noqa: F401  (kept importable from here)

from cistrack.propagation import dop853_source
from cistrack.propagation.dop853_lanes_source import RESERVED
from cistrack.propagation.lane_rhs import lane_body

__all__ = ["kernels_for", "kernel_cache_dir", "num_threads", "run_chunks", "COMPILE_SECONDS",
           "secure_cache_dir"]

_LOG = logging.getLogger("cistrack.propagation")

COMPILE_SECONDS = "10-40"
"""Rough one-time cost of compiling one model's kernels (kept for callers; the progress message
now gives an estimate for this machine, :func:`.background_compile.estimate_seconds`)."""


# -- kernel generation and caching ----------------------------------------------------------------

_LOCK = threading.Lock()
_KERNELS: dict[tuple[int, int], ModuleType] = {}


def kernel_cache_dir() -> Path:
    """Directory where generated kernel modules (and numba's cache of them) are kept.

    ``$CISTRACK_KERNEL_DIR`` (an absolute path; ConfigError for a relative one), else
    ``$XDG_CACHE_HOME/cistrack/kernels`` (an absolute path: a relative one is ignored, as the XDG
    specification says, or every working directory would get its own cache and compile afresh),
    else ``~/.cache/cistrack/kernels``; the path only (see :func:`secure_cache_dir`)."""
    env = os.environ.get("CISTRACK_KERNEL_DIR")
    if env:
        if not os.path.isabs(env):  # a relative one would make a cache (and compile afresh) in every directory
            raise ConfigError(f"environment variable CISTRACK_KERNEL_DIR={env!r}: must be an absolute path")
        return Path(env)
    xdg = os.environ.get("XDG_CACHE_HOME", "")
    base = Path(xdg) if os.path.isabs(xdg) else Path.home() / ".cache"
    return base / "cistrack" / "kernels"


def _home_problem() -> str:
    """Why the default cache, which hangs off ``$HOME``, has no home to go in ("" when it has, or
    does not hang off it): ``$HOME`` set but empty (Python then takes the root directory for the
    home), or naming a directory that does not exist (cistrack does not create a home)."""
    if os.environ.get("CISTRACK_KERNEL_DIR") or os.path.isabs(os.environ.get("XDG_CACHE_HOME", "")):
        return ""
    home = os.environ.get("HOME")
    if home is not None and not home.strip():
        return ("the environment variable HOME is empty, so there is no home directory to keep the cache in (it "
                "would have gone to /.cache)")
    if home is not None and not os.path.lexists(home):
        return f"the home directory HOME={home} does not exist, and cistrack does not create one"
    return ""


def secure_cache_dir(directory: Path | None = None) -> Path:
    """Create (mode 0700) or check the kernel cache directory; return it.

    Raises :class:`ConfigError` if it exists but is not a directory, is owned by another user, or
    is writable by group or others (code is imported from it). Raises :class:`OSError` if it
    cannot be created.
    """
    path = Path(directory) if directory is not None else kernel_cache_dir()
    where = f"kernel cache directory {path} (set CISTRACK_KERNEL_DIR to choose another)"
    problem = _home_problem() if directory is None else ""
    if problem:
        raise OSError(errno.ENOENT, problem)
    if not path.exists():
        path.mkdir(mode=0o700, parents=True, exist_ok=True)
    st = path.stat()
    if not stat.S_ISDIR(st.st_mode):
        raise ConfigError(f"{where}: exists and is not a directory")
    if hasattr(os, "getuid") and st.st_uid != os.getuid():
        raise ConfigError(f"{where}: owned by another user (uid {st.st_uid}, you are uid {os.getuid()}); "
                          "cistrack imports code from it and only uses a directory you own")
    if st.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        raise ConfigError(f"{where}: writable by group or others (mode {stat.S_IMODE(st.st_mode):o}); "
                          f"cistrack imports code from it: run chmod 700 {shlex.quote(str(path))}")
    return path


_WARNED: set[str] = set()


def _warn_uncached(exc: OSError) -> None:
    """Warn, once per process and cause, that the kernel cache directory cannot be used (``exc``
    says why) and kernels are compiled in memory: each kernel compiled had repeated it."""
    message = (f"cistrack: kernel cache directory {kernel_cache_dir()} is not usable ({exc}); compiling "
               "propagation kernels in memory (set CISTRACK_KERNEL_DIR to a writable directory of yours to cache them)")
    if message in _WARNED:
        return
    _WARNED.add(message)
    warnings.warn(message, RuntimeWarning, stacklevel=3)


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


HELPER_FILES = (Path(__file__).with_name("borrowed_view.py"),)
"""Modules whose compiled code the generated kernels embed (numba's cache of a kernel module
checks only that module's own file): their text is part of the kernel's digest."""


def _helpers_digest(files=HELPER_FILES) -> str:
    """Hash of the texts of ``files``: a changed helper gives the kernels new names, so no cached
    kernel keeps its old code."""
    return hashlib.sha256(b"".join(Path(f).read_bytes() for f in files)).hexdigest()


def _load_file_module(name: str, path: Path) -> ModuleType:
    from cistrack.lazy import tolerate_damaged_cache

    tolerate_damaged_cache()  # a damaged cache entry of the kernel is compiled again, not a traceback
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


def kernels_for(rhs: Any, dim: int = 6, body_motion: Any = None) -> ModuleType:
    """The generated module (``propagate_kernel``, ``derivatives_kernel``) for ``rhs``.

    ``body_motion`` (optional, an ``@njit`` function ``(t, params, b, body_pos) -> (x, y, z)``)
    moves the impact bodies with time; without it they sit at ``body_pos``. Built once per
    process and right-hand side; on disk once per model source and numba version.
    """
    key = (id(rhs), int(dim), id(body_motion))
    with _LOCK:
        mod = _KERNELS.get(key)
        if mod is not None:
            return mod
        where = _importable_name(rhs)
        motion_where = _importable_name(body_motion) if body_motion is not None else None
        importable = where is not None and (body_motion is None or motion_where is not None)
        mod = None
        if importable:
            motion_import = (None if body_motion is None
                             else f"from {motion_where[0]} import {motion_where[1]} as body_position")
            title = f"for {where[0]}.{where[1]}" + (f" with {motion_where[0]}.{motion_where[1]}"
                                                      if motion_where else "")
            body, names = _lanes_body(rhs)
            lanes_import = f"from {where[0]} import {', '.join(names)}\n" if names else ""
            src = dop853_source.generate_source(
                f"from {where[0]} import {where[1]} as rhs", dim, title=title, motion_import=motion_import,
                lanes=None if body is None else dop853_source.LaneKernel(body, lanes_import))
            extra = _source_digest(body_motion) if body_motion is not None else ""
            import numba  # imported here, not at module import: listing plugins needs no numba

            digest = hashlib.sha256((src + _source_digest(rhs) + extra + _helpers_digest() + numba.__version__
                                     + sys.version).encode()).hexdigest()[:20]
            name = f"cistrack_kernel_{where[1]}_{digest}"
            mod = None
            try:
                path = secure_cache_dir() / f"{name}.py"
                if not path.exists() or path.read_text() != src:
                    _write_atomic(path, src)
                mod = _load_file_module(name, path)
                if not _numba_cached(path):
                    _announce_compile(f"{where[0]}.{where[1]}")
            except OSError as exc:  # unwritable home, read-only file system: compile in memory
                _warn_uncached(exc)
        if mod is None:  # not importable or no writable directory: in memory
            body, names = _lanes_body(rhs)
            src = dop853_source.generate_source("", dim, cache=False, title="(in memory)",
                                                motion_import=None if body_motion is None else "",
                                                lanes=None if body is None else dop853_source.LaneKernel(body))
            _announce_compile(_qualified_name(rhs), cached=False)
            mod = ModuleType(f"cistrack_kernel_inmemory_{id(rhs)}")
            mod.__dict__["rhs"] = rhs  # the generated header re-wraps it for inlining
            for name in names:  # the globals the rewritten lane body reads
                mod.__dict__[name] = rhs.py_func.__globals__[name]
            if body_motion is not None:
                mod.__dict__["body_position"] = body_motion
            exec(compile(src, f"<cistrack kernel for {rhs!r}>", "exec"), mod.__dict__)
        _KERNELS[key] = mod
        return mod


def _lanes_body(rhs: Any):
    """(LaneBody or None, the global names of the rhs's module its body reads): the right-hand
    side rewritten for the SIMD-lockstep kernel, or None (why logged) to use the one-particle one."""
    body, why = lane_body(rhs, RESERVED)
    if body is None:
        _LOG.debug("no SIMD-lockstep kernel for %r: %s", rhs, why)
        return None, []
    glob = getattr(rhs, "py_func", rhs).__globals__
    return body, sorted(n for n in body.free_names if n in glob and n not in RESERVED)


def _numba_cached(path: Path) -> bool:
    """Whether numba's on-disk cache already holds a propagation kernel of module ``path`` (the
    one-particle or the lockstep one: a run with many particles compiles only the latter)."""
    return any((path.parent / "__pycache__").glob(f"{path.stem}.propagate*_kernel-*.nbi"))


def _qualified_name(rhs: Any) -> str:
    """``module.name`` of a right-hand side (of its Python function, for a numba dispatcher)."""
    func = getattr(rhs, "py_func", rhs)
    return f"{getattr(func, '__module__', '?')}.{getattr(func, '__qualname__', repr(rhs))}"


def _announce_compile(what: str, cached: bool = True) -> None:
    """Say (through logging; the command line shows it) that the next call compiles kernels, and
    about how long a run's kernels (dense and lockstep, the latter in a second process when
    there is a second core) take on this machine; ``cached``: whether later runs load them
    (False: compiled in memory, in every process)."""
    from cistrack.propagation.background_compile import estimate_seconds, idle_core

    seconds = estimate_seconds(("dense_kernel", "propagate_lanes_kernel"), parallel=idle_core())
    when = "one-time, first run here" if cached else "in memory, again in every process"
    _LOG.info("compiling propagation kernels for %s (%s: ~%.0f s)...", what, when, seconds)


# -- threads ---------------------------------------------------------------------------------------
# The worker threads are shared with the compiled mixture densities: :mod:`cistrack.threads`.
