"""The generated kernels' views without a reference count: the same memory, usable by callees."""
from __future__ import annotations

import numpy as np
from numba import njit

from cistrack.propagation.borrowed_view import borrowed_view


@njit
def _scale_in_place(a, factor):
    for i in range(a.shape[0]):
        a[i] *= factor


@njit
def _through_a_view(a, factor):
    view = borrowed_view(a)
    _scale_in_place(view, factor)
    return view.ctypes.data, view.shape[0]


def test_a_callee_writing_through_a_borrowed_view_changes_the_array_itself():
    a = np.arange(5.0)
    address, size = _through_a_view(a, 2.0)
    assert address == a.ctypes.data and size == 5
    assert np.array_equal(a, 2.0 * np.arange(5.0))


def test_a_borrowed_view_keeps_a_two_dimensional_shape_and_strides():
    @njit
    def column_sums(a):
        v = borrowed_view(a)
        return v.sum(axis=0), v.strides[0], v.shape

    a = np.arange(12.0).reshape(3, 4)
    sums, stride, shape = column_sums(a)
    assert np.array_equal(sums, a.sum(axis=0)) and stride == a.strides[0] and shape == (3, 4)


def test_the_fallback_for_a_numba_without_those_internals_is_the_array_itself():
    from cistrack.propagation.borrowed_view import _counted

    counted = njit(inline="always")(_counted)

    @njit
    def through(a):
        v = counted(a)
        _scale_in_place(v, 3.0)
        return v.ctypes.data

    a = np.ones(4)
    assert through(a) == a.ctypes.data and np.array_equal(a, np.full(4, 3.0))
