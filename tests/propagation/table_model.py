"""Models whose right-hand side reads a table by time: a record on a time grid (``k: LaneRecord``)
and a periodic table (``k: LaneUniform``, an index that goes back as time grows); and work
arrays of their SIMD-lockstep kernels for tests of the keyed stages."""
from __future__ import annotations

import numpy as np
from numba import njit

from cistrack.propagation import CompiledDynamics
from cistrack.propagation.lane_rhs import LaneRecord, LaneUniform

N_TABLE = 40


@njit
def table_rhs(t, y, p, out):
    """Oscillator pushed by a force read from a table of N_TABLE intervals of time, plus a ramp
    from each interval's start (which reads the key itself in the lane loop, as the ephemeris
    model's record time does)."""
    width = p[0]
    k: LaneRecord = min(max(int(np.floor(t / width)), 0), N_TABLE - 1)
    f = p[1 + k] + 0.01 * (t / width - k)
    for i in range(3):
        out[i] = y[i + 3]
        out[i + 3] = -y[i] + f * (i + 1)


@njit
def parity_rhs(t, y, p, out):
    """The same oscillator pushed by one of two forces, alternating every p[0] of time: its
    table index is periodic in ``t``, not monotonic."""
    width = p[0]
    k: LaneUniform = int(np.floor(t / width)) % 2
    f = p[1 + k]
    for i in range(3):
        out[i] = y[i + 3]
        out[i + 3] = -y[i] + f * (i + 1)


class Model(CompiledDynamics):
    def __init__(self, params, rtol: float = 1e-10, atol: float = 1e-12):
        self.params, self.rtol, self.atol = np.asarray(params, dtype=float), rtol, atol

    def params_vector(self):
        return self.params


class Table(Model):
    rhs = table_rhs


class Parity(Model):
    rhs = parity_rhs


def table_stage_case(seed: int = 2, model=None):
    """The kernels and parameters of ``model`` (default the Table model) and a random work array
    whose lanes are all in record 4 (times 1.05-1.06, steps of 1e-3)."""
    table = Table(np.r_[0.25, np.random.default_rng(1).normal(size=N_TABLE)]) if model is None else model
    mod, p = table._kernels(), table._params()
    lanes = mod.LANES
    w = np.random.default_rng(seed).normal(size=mod.ROWS * lanes)
    w[mod.ROW_T * lanes:(mod.ROW_T + 1) * lanes] = 1.05 + 0.01 * np.arange(lanes) / lanes  # record 4
    w[mod.ROW_H * lanes:(mod.ROW_H + 1) * lanes] = 1e-3
    return mod, p, w


def stage_output(mod, w, stage):
    """Stage ``stage``'s derivatives in ``w``, (dim, lanes)."""
    lanes, dim = mod.LANES, mod.DIM
    return w[(2 * dim + (stage - 1) * dim) * lanes:(2 * dim + stage * dim) * lanes].reshape(dim, lanes)
