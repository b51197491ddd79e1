"""Running a generated propagation kernel directly (the one-particle or the lockstep one) on the
same inputs, and comparing two runs' results exactly."""
from __future__ import annotations

import numpy as np


def run_kernel(kernel, dyn, states, times, max_steps=5_000_000, rtol=None, atol=None):
    """(out (K, N, 6), impact_body, impact_time, status) of ``kernel`` over all of ``states``."""
    n = states.shape[0]
    out = np.empty((times.size, n, 6))
    ib, it, st = np.full(n, -1), np.full(n, np.inf), np.zeros(n, dtype=np.int64)
    pos, rad = dyn._bodies_arrays()
    kernel(0, n, np.ascontiguousarray(states), dyn._params(), 0.0, times, dyn.rtol if rtol is None else rtol,
           dyn.atol if atol is None else atol, pos, rad, max_steps, np.zeros(n), out, ib, it, st)
    return out, ib, it, st


def same_results(a, b) -> bool:
    """Whether two :func:`run_kernel` results are equal bit for bit."""
    return all(np.array_equal(u, v) for u, v in zip(a, b))
