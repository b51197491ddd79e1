"""The ``cistrack`` executable loads scipy.linalg's two binding modules alone (cistrack.console):
a run then imports neither scipy.linalg nor scipy.special (about 0.1 s of CPU each), numba's
BLAS still works, and scipy.linalg, imported later, is whole and holds those same modules."""
from __future__ import annotations

import subprocess
import sys
import textwrap

SMALL = ["--set", "duration_days=1.4", "--set", "filter.n_particles=300", "--set", "filter.n_components=2",
         "--set", "iod.n_particles=300"]


def _child(code: str, tmp_path) -> list[str]:
    proc = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True,
                          cwd=tmp_path, timeout=600)
    assert proc.returncode == 0, proc.stderr
    return proc.stdout.strip().splitlines()


def test_a_run_of_the_executable_imports_neither_scipy_linalg_nor_scipy_special(tmp_path):
    lines = _child(f"""
        import atexit, sys
        atexit.register(lambda: print("LOADED", "scipy.linalg" in sys.modules, "scipy.special" in sys.modules))
        sys.argv = ["cistrack", "run", "quick", "--quiet", "--out", "r", *{SMALL!r}]
        from cistrack.console import console_main
        console_main()
        """, tmp_path)
    assert lines[-1] == "LOADED False False"


def test_numba_blas_works_and_scipy_linalg_imported_later_holds_the_same_modules(tmp_path):
    lines = _child("""
        import sys
        import numpy as np
        from cistrack.console import load_lapack_bindings
        loaded = load_lapack_bindings()
        print(sorted(loaded), "scipy.linalg" in sys.modules)
        import numba

        @numba.njit
        def product(a, b):
            return np.dot(a, b)

        a = np.arange(9.0).reshape(3, 3)
        print(np.array_equal(product(a, a), a @ a), "scipy.linalg" in sys.modules)
        import scipy.linalg
        print(scipy.linalg.cython_blas is loaded["cython_blas"], scipy.linalg.cython_lapack is loaded["cython_lapack"],
              np.allclose(scipy.linalg.cholesky(a @ a.T + np.eye(3)).T @ scipy.linalg.cholesky(a @ a.T + np.eye(3)),
                          a @ a.T + np.eye(3)))
        """, tmp_path)
    assert lines == ["['cython_blas', 'cython_lapack'] False", "True False", "True True True"]


def test_nothing_is_loaded_alone_where_scipy_linalg_is_already_imported(tmp_path):
    lines = _child("""
        import sys
        import scipy.linalg
        from cistrack.console import load_lapack_bindings
        print(load_lapack_bindings(), [type(f).__name__ for f in sys.meta_path if "Attach" in type(f).__name__])
        """, tmp_path)
    assert lines == ["{} []"]
