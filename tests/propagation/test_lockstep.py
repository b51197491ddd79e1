"""The SIMD-lockstep integrator: the one-particle kernel's results bit for bit, for models whose
right-hand side can be rewritten into lane code; every other model keeps the one-particle kernel."""
from __future__ import annotations

import numpy as np
import pytest
from numba import njit

from cistrack.plugins.dynamics.orbit_catalog import ORBITS
from cistrack.plugins.dynamics.cr3bp import CR3BP, cr3bp_rhs
from cistrack.plugins.dynamics.twobody import TwoBody
from cistrack.propagation.dop853_lanes_source import RESERVED
from cistrack.propagation.lane_rhs import lane_body

from .kernel_runs import run_kernel as _run, same_results as _same

NRHO = ORBITS["nrho-9-2"]


def _mixed_ensemble(dyn, n, seed=3):
    """NRHO particles, two aimed at the Moon and one starting inside the Earth."""
    rng = np.random.default_rng(seed)
    cloud = NRHO.state + rng.normal(size=(n, 6)) * np.r_[[3e-5] * 3, [1e-4] * 3]
    moon = np.array([1.0 - dyn.mu, 0.0, 0.0])
    cloud[5] = np.r_[moon + [0.0, 0.05, 0.01], [0.02, -0.5, 0.0]]
    cloud[17] = np.r_[moon + [0.0, 0.05, 0.01], [0.03, -0.5, 0.0]]
    cloud[30] = [-dyn.mu + 1e-3, 0, 0, 0, 0.1, 0]
    return cloud


@pytest.mark.parametrize("times", [np.array([0.2, 0.2, 0.9, 2.0]), np.array([-0.4, -1.3])],
                         ids=["forward, repeated output time", "backward"])
def test_lockstep_results_equal_the_one_particle_kernel_bit_for_bit(times):
    dyn = CR3BP()
    mod = dyn._kernels()
    states = _mixed_ensemble(dyn, 53)  # not a multiple of the lane count
    one = _run(mod.propagate_kernel, dyn, states, times)
    lock = _run(mod.propagate_lanes_kernel, dyn, states, times)
    assert _same(one, lock)
    if times[-1] > 0:
        assert (one[3] == 1).sum() >= 3  # the impacts were exercised


def test_lockstep_step_limit_and_status_equal_the_one_particle_kernel():
    dyn = CR3BP()
    mod = dyn._kernels()
    states = _mixed_ensemble(dyn, 40)
    one = _run(mod.propagate_kernel, dyn, states, np.array([1.0]), max_steps=20)
    lock = _run(mod.propagate_lanes_kernel, dyn, states, np.array([1.0]), max_steps=20)
    assert (one[3] == 2).any() and _same(one, lock)


def test_propagate_goes_through_the_lockstep_kernel_for_straight_line_models():
    for dyn in (CR3BP(), TwoBody()):
        assert hasattr(dyn._kernels(), "propagate_lanes_kernel"), type(dyn).__name__


def test_the_cr3bp_right_hand_side_is_rewritten_to_lane_code():
    body, why = lane_body(cr3bp_rhs, RESERVED)
    assert why == "" and "_y0" in body.text and "__OUT__[5]" in body.text and "_p[0]" in body.text
    assert body.free_names == {"np"}


def _indexed_by_loop(t, y, p, out):
    for i in range(int(p[1])):  # a bound known only at run time: not unrolled
        out[i] = -p[0] * y[i]


def _passes_state_on(t, y, p, out):
    out[:] = np.sin(y)


def _returns_early(t, y, p, out):
    if t > 1.0:
        return
    out[0] = y[0]


def _reads_a_kernel_name(t, y, p, out):
    out[0] = LANES * y[0]  # noqa: F821


@pytest.mark.parametrize("func,reason", [(_indexed_by_loop, "integer literal"),
                                         (_passes_state_on, "integer literal"),
                                         (_returns_early, "return"),
                                         (_reads_a_kernel_name, "LANES")])
def test_right_hand_sides_that_cannot_be_rewritten_are_refused_with_the_reason(func, reason):
    body, why = lane_body(func, RESERVED)
    assert body is None and reason in why


def test_a_model_without_a_lockstep_kernel_still_propagates():
    from cistrack.propagation import CompiledDynamics

    @njit
    def loop_rhs(t, y, p, out):
        for i in range(int(p[1])):
            out[i] = -p[0] * y[i]

    class Decay(CompiledDynamics):
        rhs = loop_rhs

        def __init__(self, rtol: float = 1e-12, atol: float = 1e-14):
            self.rtol, self.atol = rtol, atol

        def params_vector(self):
            return np.array([0.5, 6.0])

    dyn = Decay()
    assert not hasattr(dyn._kernels(), "propagate_lanes_kernel")
    np.testing.assert_allclose(dyn.propagate(np.ones((40, 6)), 0.0, 2.0).final, np.exp(-1.0), rtol=1e-10)
