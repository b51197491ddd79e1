"""The upper Cholesky factor as ``scipy.linalg.cholesky`` computes it, bit for bit, without
importing ``scipy.linalg``.

Both call LAPACK's ``dpotrf`` of scipy's own LAPACK library on a column-major copy of the
matrix, reading its upper triangle; this module calls that routine through the function pointer
``scipy.linalg.cython_lapack`` exports, so the numbers are the same. Importing ``scipy.linalg``
itself costs 0.07-0.1 s of CPU (its array-API layer), which the ``cistrack`` executable spares
by loading ``cython_lapack`` alone (:mod:`cistrack.console`); elsewhere ``cython_lapack`` is
imported as usual. Where scipy exports ``dpotrf`` with another signature (a 64-bit-integer LAPACK
build), :func:`upper_cholesky` calls ``scipy.linalg.cholesky`` instead.
"""
from __future__ import annotations

import ctypes
import importlib
from functools import lru_cache
from typing import Callable

import numpy as np

__all__ = ["upper_cholesky"]

_LAPACK = "scipy.linalg.cython_lapack"
_SIGNATURE = b"void (char *, int *, __pyx_t_5scipy_6linalg_13cython_lapack_d *, int *, int *)"
"""The C signature scipy's capsule names for dpotrf(uplo, n, a, lda, info) with 32-bit integers."""
_INT_P = ctypes.POINTER(ctypes.c_int)


@lru_cache(maxsize=1)
def _dpotrf() -> Callable | None:
    """LAPACK's dpotrf from scipy's library as a ctypes function, or None where scipy does not
    export it with :data:`_SIGNATURE`."""
    capsule = getattr(importlib.import_module(_LAPACK), "__pyx_capi__", {}).get("dpotrf")
    if capsule is None:
        return None
    name_of, pointer_of = ctypes.pythonapi.PyCapsule_GetName, ctypes.pythonapi.PyCapsule_GetPointer
    name_of.restype, name_of.argtypes = ctypes.c_char_p, [ctypes.py_object]
    pointer_of.restype, pointer_of.argtypes = ctypes.c_void_p, [ctypes.py_object, ctypes.c_char_p]
    name = name_of(capsule)
    if name != _SIGNATURE:
        return None
    kind = ctypes.CFUNCTYPE(None, ctypes.c_char_p, _INT_P, ctypes.c_void_p, _INT_P, _INT_P)
    return kind(pointer_of(capsule, name))


def upper_cholesky(P: np.ndarray) -> np.ndarray:
    """U with U^T U = P, upper triangular, for each matrix of ``P`` (..., n, n), from its upper
    triangle: ``scipy.linalg.cholesky(P)`` (``lower=False``), the same numbers and errors
    (ValueError for a non-finite entry, ``numpy.linalg.LinAlgError`` where a leading minor is not
    positive definite). Returns an array of ``P``'s shape."""
    routine = _dpotrf()
    if routine is None:
        from scipy.linalg import cholesky

        return cholesky(P)
    P = np.asarray(P, dtype=float)
    if P.ndim < 2 or P.shape[-1] != P.shape[-2]:
        raise ValueError(f"a Cholesky factor needs square matrices (..., n, n), got shape {P.shape}")
    if not np.all(np.isfinite(P)):
        raise ValueError("array must not contain infs or NaNs")
    n = P.shape[-1]
    out = np.empty_like(P)
    size, info = ctypes.c_int(n), ctypes.c_int(0)
    for k in np.ndindex(P.shape[:-2]):
        a = np.array(P[k], order="F")
        routine(b"U", ctypes.byref(size), a.ctypes.data, ctypes.byref(size), ctypes.byref(info))
        if info.value > 0:
            raise np.linalg.LinAlgError(f"{info.value}-th leading minor of the array is not positive definite")
        out[k] = np.triu(a)
    return out
