"""Views of an array without a reference count, for the generated kernels' hot calls.

numba counts references to every array a compiled function receives: the callee increments the
array's count on entry and decrements it on return, two atomic (``lock``-prefixed) operations
each. The SIMD-lockstep kernel calls 14 or more functions with its work array and parameter
vector per step of a batch (``_lanes_step``, ``_lanes_keys``, one per stage, the error estimate),
and those atomics are a sizeable share of a propagation's CPU. :func:`borrowed_view` gives the same
data, shape and strides with no memory-info pointer: numba's increments and decrements then test
a null pointer and return. The arithmetic is untouched, so results are the same bit for bit.

The view does not keep the array alive: the caller must hold the array itself for as long as
the view is used (the kernels create the view from an argument or from a work array they keep
using). Imported by generated kernel modules only (it loads numba).
"""
from __future__ import annotations

from numba import njit, types
from numba.extending import intrinsic

try:  # numba's array internals (numba 0.49 to 0.68 at least)
    from numba.np.arrayobj import make_array, populate_array
except ImportError:  # pragma: no cover - a numba that moved them: plain arrays, counted as before
    make_array = populate_array = None

__all__ = ["borrowed_view"]


def _counted(arr):
    """The array itself (reference counted): the fallback when numba's internals moved."""
    return arr


@intrinsic
def _borrowed_view(typingctx, arr):
    """``arr`` (any shape, any dtype) -> the same array without reference counting (compiled code only)."""
    if not isinstance(arr, types.Array):
        return None

    def codegen(context, builder, signature, args):
        aryty = signature.args[0]
        src = make_array(aryty)(context, builder, value=args[0])
        view = make_array(signature.return_type)(context, builder)
        populate_array(view, data=src.data, shape=src.shape, strides=src.strides,
                       itemsize=src.itemsize, meminfo=None)
        return view._getvalue()

    return arr(arr), codegen


borrowed_view = _borrowed_view if populate_array is not None else njit(inline="always")(_counted)
