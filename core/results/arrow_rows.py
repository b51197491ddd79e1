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

from itertools import chain
from typing import Any

import numpy as np

__all__ = ["table_from_rows"]

_INT64_MIN, _INT64_MAX = -(2 ** 63), 2 ** 63 - 1
_EXACT_IN_DOUBLE = 2 ** 53
_NONE = type(None)
_FLOATS = frozenset({float, np.float64})
_INTS = frozenset({int, np.int64})
_BOOLS = frozenset({bool, np.bool_})
_LISTS = frozenset({list, tuple})


def _validity(valid: np.ndarray | None):
    """Arrow validity bitmap (None when every value is present)."""
    import pyarrow as pa

    return None if valid is None else pa.py_buffer(np.packbits(valid, bitorder="little"))


def _spread(present: list, valid: np.ndarray | None, dtype) -> np.ndarray:
    """The present values at their rows of a zero-filled array (all rows when ``valid`` is None)."""
    if valid is None:
        return np.array(present, dtype=dtype)
    data = np.zeros(valid.size, dtype=dtype)
    data[valid] = np.array(present, dtype=dtype)
    return data


def _numbers(present: list, valid: np.ndarray | None, n: int, types: set):
    """Python/numpy ints and floats: int64 when all are ints, else double; None when an int does
    not fit (int64, or exactly in a double when mixed with floats)."""
    import pyarrow as pa

    ints = types & _INTS
    if ints:
        values = present if not types - _INTS else [v for v in present if type(v) in _INTS]
        lo, hi = min(values), max(values)
        bound = _EXACT_IN_DOUBLE if types - _INTS else _INT64_MAX
        if lo < max(_INT64_MIN, -bound) or hi > bound:
            return None
    dtype, atype = (np.int64, pa.int64()) if types <= _INTS else (np.float64, pa.float64())
    return pa.Array.from_buffers(atype, n, [_validity(valid), pa.py_buffer(_spread(present, valid, dtype))])


def _offsets(lengths: list) -> np.ndarray | None:
    """Arrow int32 offsets (n + 1,) of items of ``lengths``; None beyond int32."""
    offsets = np.zeros(len(lengths) + 1, dtype=np.int64)
    np.cumsum(lengths, out=offsets[1:])
    return None if offsets[-1] > np.iinfo(np.int32).max else offsets.astype(np.int32)


def _column(values: list):
    """The Arrow array of one column, or None when it is left to ``from_pydict``."""
    import pyarrow as pa

    n = len(values)
    types = set(map(type, values))
    valid = None
    present = values
    if _NONE in types:
        types.discard(_NONE)
        if not types:
            return pa.nulls(n)
        valid = np.array([v is not None for v in values], dtype=bool)
        present = [v for v in values if v is not None]
    if types <= _FLOATS | _INTS:
        return _numbers(present, valid, n, types)
    if types <= _BOOLS:
        bits = _spread(present, valid, bool)
        return pa.Array.from_buffers(pa.bool_(), n, [_validity(valid), pa.py_buffer(np.packbits(bits, bitorder="little"))])
    if types == {str}:
        encoded = [v.encode("utf-8") for v in present]
        lengths = _spread(list(map(len, encoded)), valid, np.int64)
        offsets = _offsets(lengths)
        if offsets is None:
            return None
        return pa.Array.from_buffers(pa.string(), n, [_validity(valid), pa.py_buffer(offsets),
                                                      pa.py_buffer(b"".join(encoded))])
    if types <= _LISTS:  # lists of numbers: list<double>, or list<int64> when every item is an int
        flat = list(chain.from_iterable(present))
        inner = set(map(type, flat))
        if not flat or not inner <= _FLOATS | _INTS:
            return None  # empty lists only, nulls or other kinds inside: from_pydict types those
        child = _numbers(flat, None, len(flat), inner)
        offsets = _offsets(_spread(list(map(len, present)), valid, np.int64))
        if child is None or offsets is None:
            return None
        return pa.Array.from_buffers(pa.list_(child.type), n, [_validity(valid), pa.py_buffer(offsets)],
                                     children=[child])
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
