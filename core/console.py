"""The ``cistrack`` executable: BLAS libraries loaded with one thread, the collector paused while
its modules load, then the command.

Every run does its linear algebra with one BLAS thread (``blas_threads``, default 1, of
:func:`cistrack.runs.pipeline.run_scenario`: many small matrices), and a least-squares fit's
matrices are as small. A BLAS library loaded with more threads still costs CPU: OpenBLAS starts
its thread pool when it loads and its threads spin for about 0.1 s of CPU before they sleep, once
for numpy's OpenBLAS and once for scipy's, so about 0.13 s of a 1.9 s ``cistrack run example-1``
process went to threads that never did any work (``benchmarks/process_timeline.py``: importing
numpy 0.113 s CPU against 0.060 s wall, numba's target context, which imports scipy.linalg, 0.384
s against 0.282 s). So before anything imports numpy this module sets ``$OPENBLAS_NUM_THREADS``,
``$MKL_NUM_THREADS`` and ``$BLIS_NUM_THREADS`` to 1 where they are unset; a variable the user set
is left as it is. Worker processes of a study inherit them. Importing :mod:`cistrack.cli` from
Python changes nothing in the process's environment: only the executable does this.

The cyclic garbage collector is paused while the command's modules load, and the objects they
made are then frozen (:func:`gc.freeze`) before it resumes: module-level objects live as long as
the process, yet every full collection walked them again. In a ``cistrack run example-1`` process
the collector's passes took 0.084 s (``gc.callbacks``: about 290 collections, one full one of
0.041 s early in the run), 0.046 s with this. The whole process's CPU time fell by about 1 %
(new/old 0.978-1.007 over three alternated runs of 15-25 pairs): within this shared machine's
spread, the system time rising a little where the user time fell. The command itself runs with
the collector on; a frozen object is never collected, which for the modules' own objects changes
nothing.

numba's target context, set up when the first compiled kernel loads, checks that BLAS is there by
importing ``scipy.linalg.cython_blas``, and so the whole of ``scipy.linalg`` (0.07-0.1 s of CPU,
most of it scipy's array-API layer), which a run does not otherwise need (its Cholesky factors
come from ``cython_lapack``: :mod:`cistrack.numerics.cholesky`). The executable loads those two
extension modules from their files first (:func:`load_lapack_bindings`); ``scipy.linalg``, when
something imports it later, loads as usual and finds them there.
"""
from __future__ import annotations

import gc
import importlib.machinery
import importlib.util
import os
import sys
from types import ModuleType

__all__ = ["BLAS_THREAD_VARIABLES", "LAPACK_BINDINGS", "console_main", "load_lapack_bindings"]

BLAS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS")
"""The variables a BLAS library reads for its thread count when it loads."""
LAPACK_BINDINGS = ("scipy.linalg.cython_blas", "scipy.linalg.cython_lapack")
"""What numba's BLAS check and :mod:`cistrack.numerics.cholesky` import from ``scipy.linalg``."""
_PACKAGE = "scipy.linalg"


class _AttachToPackage:
    """A one-use import finder: when ``scipy.linalg`` loads after :func:`load_lapack_bindings`,
    its modules loaded alone become its attributes, as a normal import of them would have made
    them."""

    def __init__(self, modules: dict[str, ModuleType]):
        self.modules = modules

    def find_spec(self, fullname: str, path=None, target=None):
        if fullname != _PACKAGE:
            return None
        sys.meta_path.remove(self)
        spec = importlib.machinery.PathFinder.find_spec(fullname, path)
        if spec is None or spec.loader is None:
            return spec
        run = spec.loader.exec_module

        def exec_module(module: ModuleType) -> None:
            run(module)
            for name, loaded in self.modules.items():
                if not hasattr(module, name):
                    setattr(module, name, loaded)

        spec.loader.exec_module = exec_module
        return spec


def _load_alone(qualified: str, folder: str) -> ModuleType | None:
    """The extension module ``qualified`` loaded from ``folder`` without its package; None where
    its file is not there or it fails to load (then nothing is left behind)."""
    name = qualified.rpartition(".")[2]
    path = next((os.path.join(folder, name + suffix) for suffix in importlib.machinery.EXTENSION_SUFFIXES
                 if os.path.isfile(os.path.join(folder, name + suffix))), None)
    if path is None:
        return None
    spec = importlib.util.spec_from_file_location(qualified, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[qualified] = module
    try:
        spec.loader.exec_module(module)
    except Exception:  # an unusual scipy: leave the import to its users, as without this
        del sys.modules[qualified]
        return None
    return module


def load_lapack_bindings() -> dict[str, ModuleType]:
    """Load :data:`LAPACK_BINDINGS` from their files without their package (``scipy.linalg``)
    and return them by short name; nothing where scipy.linalg or one of them is already loaded,
    or scipy is not found."""
    if _PACKAGE in sys.modules or any(m in sys.modules for m in LAPACK_BINDINGS):
        return {}
    scipy = importlib.util.find_spec("scipy")
    if scipy is None or not scipy.submodule_search_locations:
        return {}
    folder = os.path.join(list(scipy.submodule_search_locations)[0], "linalg")
    loaded = {q.rpartition(".")[2]: m for q in LAPACK_BINDINGS if (m := _load_alone(q, folder)) is not None}
    if loaded:
        sys.meta_path.insert(0, _AttachToPackage(loaded))
    return loaded


def console_main() -> None:
    """The ``cistrack`` command (:func:`cistrack.cli.main.console_main`), its BLAS libraries
    loaded with one thread unless the environment says otherwise."""
    for name in BLAS_THREAD_VARIABLES:
        if not os.environ.get(name, "").strip():
            os.environ[name] = "1"
    gc.disable()
    try:
        load_lapack_bindings()
        from cistrack.cli.main import console_main as command
    except KeyboardInterrupt:  # Ctrl-C while the command is still loading (before its handlers exist)
        sys.stderr.write("cistrack: interrupted (SIGINT) while starting; nothing was done\n")
        raise SystemExit(130) from None
    finally:
        gc.freeze()
        gc.enable()
    command()
