"""Carried step sizes: ``propagate(..., steps=h)`` starts each particle with the step its previous
integration proposed (no initial-step estimate) and returns the next proposal; error control, and
so the accuracy, are those of a fresh start."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from cistrack.errors import PropagationError, StateError
from cistrack.plugins.dynamics.cr3bp import CR3BP
from cistrack.plugins.dynamics.ephemeris import EphemerisDynamics
from cistrack.plugins.dynamics.orbit_catalog import ORBITS

from .kernel_runs import same_results

NRHO = ORBITS["nrho-9-2"]


def _cloud(n, seed=5):
    rng = np.random.default_rng(seed)
    return NRHO.state + rng.normal(size=(n, 6)) * np.r_[[3e-5] * 3, [1e-5] * 3]


def _kernel_with_steps(kernel, dyn, states, times, steps):
    n = states.shape[0]
    out = np.empty((times.size, n, 6))
    ib, it, st = np.full(n, -1), np.full(n, np.inf), np.zeros(n, dtype=np.int64)
    pos, rad = dyn._bodies_arrays()
    h = np.array(steps, dtype=float)
    kernel(0, n, states, dyn._params(), 0.0, times, dyn.rtol, dyn.atol, pos, rad, dyn.max_steps, h, out, ib, it, st)
    return out, ib, it, st, h


def test_the_lockstep_kernel_carries_steps_exactly_as_the_one_particle_kernel():
    dyn = CR3BP()
    mod = dyn._kernels()
    states = _cloud(37)
    steps = np.where(np.arange(37) % 3 == 0, 0.0, np.linspace(1e-4, 0.05, 37))
    times = np.array([0.01, 0.3])
    one = _kernel_with_steps(mod.propagate_kernel, dyn, states, times, steps)
    lock = _kernel_with_steps(mod.propagate_lanes_kernel, dyn, states, times, steps)
    assert same_results(one, lock)


def test_the_lockstep_kernel_carries_steps_exactly_as_the_one_particle_kernel_for_a_time_dependent_model():
    # the ephemeris model: time enters the right-hand side, and its lane code reads a table
    # keyed by time; carried and fresh starts mixed, lanes refilled while others are mid-step
    dyn = EphemerisDynamics(epoch="2026-01-01T00:00:00Z", j2=True)
    times = np.array([0.004, 0.35, 0.9])
    dyn._ensure_window(0.0, times[-1])
    states = dyn.to_inertial(_cloud(45), 0.0)
    steps = np.where(np.arange(45) % 4 == 0, 0.0, np.linspace(1e-3, 0.08, 45))
    mod = dyn._kernels()
    one = _kernel_with_steps(mod.propagate_kernel, dyn, states, times, steps)
    lock = _kernel_with_steps(mod.propagate_lanes_kernel, dyn, states, times, steps)
    assert same_results(one, lock)


def test_a_carried_step_is_the_first_step_taken():
    dyn = CR3BP()
    dyn.max_steps = 1
    x = _cloud(8)
    span = 0.04  # 4 hours near apolune: the error control proposes ~0.12 TU here
    got = dyn.propagate(x, 0.0, span, steps=np.full(8, 0.12))
    assert np.all(got.alive)
    with pytest.raises(PropagationError, match="max_steps"):  # the initial-step estimate starts smaller
        dyn.propagate(x, 0.0, span)


def test_propagation_returns_the_next_step_of_every_particle():
    dyn = CR3BP()
    got = dyn.propagate(_cloud(20), 0.0, [0.1, 0.2])
    assert got.steps.shape == (20,) and np.all(got.steps > 0)
    none = dyn.propagate(_cloud(20), 0.0, 0.0, steps=np.full(20, 0.125))  # no step taken: kept
    assert np.all(none.steps == 0.125)


def test_a_particle_that_hits_a_body_returns_no_step():
    dyn = CR3BP()
    x = _cloud(6)
    x[2] = [1.0 - dyn.mu + 0.05, 0.0, 0.0, -0.5, 0.0, 0.0]  # aimed at the Moon
    got = dyn.propagate(x, 0.0, 0.5)
    assert not got.alive[2] and got.steps[2] == 0.0 and np.all(got.steps[got.alive] > 0)


def test_steps_of_the_wrong_shape_are_refused_by_name():
    with pytest.raises(StateError, match="steps must be 4 finite step sizes"):
        CR3BP().propagate(_cloud(4), 0.0, 0.1, steps=np.ones(3))
    with pytest.raises(StateError, match="steps"):
        CR3BP().propagate(_cloud(4), 0.0, 0.1, steps=[np.nan] * 4)


def test_a_period_in_many_calls_with_carried_steps_is_as_accurate_as_one_call():
    """Against scipy's DOP853 at rtol 1e-13: 60 calls that carry their steps stay within the error
    of one call over the period (both about 1e-9 LU at the default tolerance)."""
    dyn = CR3BP()
    x0 = _cloud(4)
    times = np.linspace(0.0, NRHO.period, 61)[1:]
    one = dyn.propagate(x0, 0.0, NRHO.period).final
    x, h = x0, None
    for t0, t1 in zip(np.r_[0.0, times[:-1]], times):
        p = dyn.propagate(x, t0, t1, steps=h)
        x, h = p.final, p.steps
    ref = np.array([solve_ivp(lambda t, y: dyn.derivatives(t, y[None])[0], (0.0, NRHO.period), s,
                              method="DOP853", rtol=1e-13, atol=1e-14).y[:, -1] for s in x0])
    err_one = np.abs(one[:, :3] - ref[:, :3]).max()
    err_carried = np.abs(x[:, :3] - ref[:, :3]).max()
    assert err_carried < max(10 * err_one, 1e-9), (err_carried, err_one)
