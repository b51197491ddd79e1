"""Rows of Python values as an Arrow table, built from numpy buffers where the values allow it.

Why: ``pa.array`` (and so ``pa.Table.from_pydict``) imports pandas the first time it converts
anything, to check whether the values are pandas objects: about 0.2 s at the end of every run
process that writes results (measured on Example 1: 0.20 s of a 2.1 s process), for tables that
hold only numbers, strings and lists of numbers. :func:`table_from_rows` builds such columns
with ``pa.Array.from_buffers``, which imports nothing, and gives the table ``from_pydict`` gives:
the same column order, types, values, NaNs and nulls (``tests/results/test_arrow_rows.py``
compares the two on the results tables of real runs and on generated rows). A column of any
other kind (mixed kinds, nested lists, lists with nulls, other numpy widths, bytes, dates...) is
left to ``from_pydict``, as before.
"""
from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["table_from_rows"]

_INT64_MIN, _INT64_MAX = -(2 ** 63), 2 ** 63 - 1
_EXACT_IN_DOUBLE = 2 ** 53


def _kind(v: Any) -> str | None:
    """None, "bool", "int", "float", "str", "list" or "other" (the kinds converted here)."""
    if v is None:
        return None
    t = type(v)
    if t is bool or t is np.bool_:
        return "bool"
    if t is int or t is np.int64:
        return "int"
    if t is float or t is np.float64:
        return "float"
    if t is str:
        return "str"
    if t is list or t is tuple:
        return "list"
    return "other"


def _validity(valid: np.ndarray):
    """Arrow validity bitmap (None when every value is present)."""
    import pyarrow as pa

    return None if valid.all() else pa.py_buffer(np.packbits(valid, bitorder="little"))


def _numbers(values: list, valid: np.ndarray, kinds: set[str]):
    """Values of kinds {"int"}, {"float"} or {"int", "float"} (None where not ``valid``): int64,
    double or double; None when an int does not fit (int64, or exactly in a double when mixed)."""
    import pyarrow as pa

    present = [v for v in values if v is not None]
    if "int" in kinds:
        ints = [int(v) for v in present if type(v) is not float and type(v) is not np.float64]
        if ints:
            bound = _EXACT_IN_DOUBLE if "float" in kinds else None
            lo, hi = min(ints), max(ints)
            if lo < _INT64_MIN or hi > _INT64_MAX or (bound is not None and max(-lo, hi) > bound):
                return None
    dtype, atype = (np.int64, pa.int64()) if kinds == {"int"} else (np.float64, pa.float64())
    data = np.zeros(len(values), dtype=dtype)
    data[valid] = np.array(present, dtype=dtype)
    return pa.Array.from_buffers(atype, len(values), [_validity(valid), pa.py_buffer(data)])


def _booleans(values: list, valid: np.ndarray):
    import pyarrow as pa

    bits = np.array([bool(v) if v is not None else False for v in values], dtype=bool)
    return pa.Array.from_buffers(pa.bool_(), len(values),
                                 [_validity(valid), pa.py_buffer(np.packbits(bits, bitorder="little"))])


def _strings(values: list, valid: np.ndarray):
    import pyarrow as pa

    encoded = [v.encode("utf-8") if v is not None else b"" for v in values]
    offsets = np.zeros(len(values) + 1, dtype=np.int64)
    np.cumsum([len(b) for b in encoded], out=offsets[1:])
    if offsets[-1] > np.iinfo(np.int32).max:
        return None
    return pa.Array.from_buffers(pa.string(), len(values),
                                 [_validity(valid), pa.py_buffer(offsets.astype(np.int32)),
                                  pa.py_buffer(b"".join(encoded))])


def _lists(values: list, valid: np.ndarray):
    """Lists of numbers: list<double> (or list<int64> when every element is an int); None for
    anything else (nulls or other kinds inside, or only empty lists: from_pydict types those)."""
    import pyarrow as pa

    flat = [x for v in values if v is not None for x in v]
    inner = {_kind(x) for x in flat}
    if not flat or not inner <= {"int", "float"}:
        return None
    child = _numbers(flat, np.ones(len(flat), dtype=bool), inner)
    if child is None:
        return None
    offsets = np.zeros(len(values) + 1, dtype=np.int64)
    np.cumsum([len(v) if v is not None else 0 for v in values], out=offsets[1:])
    if offsets[-1] > np.iinfo(np.int32).max:
        return None
    return pa.Array.from_buffers(pa.list_(child.type), len(values),
                                 [_validity(valid), pa.py_buffer(offsets.astype(np.int32))], children=[child])


def _column(values: list):
    """The Arrow array of one column, or None when it is left to ``from_pydict``."""
    import pyarrow as pa

    kinds = {_kind(v) for v in values} - {None}
    valid = np.array([v is not None for v in values], dtype=bool)
    if not kinds:
        return pa.nulls(len(values))
    if kinds <= {"int", "float"}:
        return _numbers(values, valid, kinds)
    if kinds == {"bool"}:
        return _booleans(values, valid)
    if kinds == {"str"}:
        return _strings(values, valid)
    if kinds == {"list"}:
        return _lists(values, valid)
    return None


def table_from_rows(rows: list[dict[str, Any]]):
    """``pa.Table.from_pydict`` of ``rows`` with the union of their keys in order of first
    appearance (a key missing from a row is null there); see the module for why and how."""
    import pyarrow as pa

    keys = list(dict.fromkeys(k for r in rows for k in r))
    columns = {k: [r.get(k) for r in rows] for k in keys}
    arrays = []
    for k in keys:
        arr = _column(columns[k])
        if arr is None:
            return pa.Table.from_pydict(columns)
        arrays.append(arr)
    return pa.Table.from_arrays(arrays, names=keys)
