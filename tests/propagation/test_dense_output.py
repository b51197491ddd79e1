"""Dense output: one integration, the state at any time of the span, as accurate as the steps.

Checked against an independent plain-scipy CR3BP integrated at rtol 1e-13 (tests/reference_cr3bp.py)
at arbitrary times, and against cistrack's own ensemble propagation (same steps, same end state)."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from cistrack.errors import StateError
from cistrack.plugins.dynamics.orbit_catalog import ORBITS
from cistrack.plugins.dynamics.cr3bp import CR3BP

from reference_cr3bp import cr3bp_rhs  # tests/ is on sys.path

NRHO = ORBITS["nrho-9-2"]


def _reference(x0, times):
    return solve_ivp(cr3bp_rhs, (0.0, float(times[-1])), x0, method="DOP853", rtol=1e-13, atol=1e-15,
                     t_eval=times).y.T


def _random_times(span, n=150, seed=7):
    return np.sort(np.random.default_rng(seed).uniform(0.0, span, n))


def test_dense_states_at_arbitrary_times_match_a_tight_reference_at_the_default_tolerance():
    dyn = CR3BP()
    times = _random_times(NRHO.period)
    traj = dyn.dense_trajectory(NRHO.state, 0.0, NRHO.period)
    err = np.abs(traj.states(times) - _reference(NRHO.state, times)).max()
    assert err <= 1e-9


def test_dense_output_converges_with_the_tolerance():
    """A wrong interpolation coefficient leaves an error floor far above 1e-12; a right one
    follows the integrator down."""
    dyn = CR3BP()
    times = _random_times(NRHO.period)
    traj = dyn.dense_trajectory(NRHO.state, 0.0, NRHO.period, rtol=1e-14, atol=1e-15)
    assert np.abs(traj.states(times) - _reference(NRHO.state, times)).max() <= 1e-11


def test_the_span_end_is_bit_identical_to_a_propagation_to_that_time():
    dyn = CR3BP()
    traj = dyn.dense_trajectory(NRHO.state, 0.0, 0.9)
    np.testing.assert_array_equal(traj.states(0.9)[0], dyn.propagate(NRHO.state, 0.0, 0.9).final[0])


def test_step_starts_are_the_integrator_states_exactly():
    traj = CR3BP().dense_trajectory(NRHO.state, 0.0, NRHO.period)
    np.testing.assert_array_equal(traj.states(traj.step_start), traj.step_state)


def test_a_long_span_outgrowing_the_step_records_continues_seamlessly():
    dyn = CR3BP()
    span = 6 * NRHO.period  # ~500 steps: the records grow (and the kernel resumes) at least once
    traj = dyn.dense_trajectory(NRHO.state, 0.0, span)
    assert traj.step_start.size > 256
    assert np.all(np.diff(traj.step_start) > 0)
    np.testing.assert_allclose(traj.step_start[1:], traj.step_start[:-1] + traj.step_size[:-1], rtol=0, atol=1e-15)
    np.testing.assert_array_equal(traj.states(span)[0], dyn.propagate(NRHO.state, 0.0, span).final[0])


def test_backward_spans_are_evaluated_like_forward_ones():
    dyn = CR3BP()
    fwd = dyn.propagate(NRHO.state, 0.0, 0.5).final[0]
    back = dyn.dense_trajectory(fwd, 0.5, 0.0)
    times = np.array([0.4, 0.25, 0.1, 0.0])
    np.testing.assert_allclose(back.states(times), _reference(NRHO.state, times[::-1])[::-1], rtol=0, atol=1e-9)


def test_a_trajectory_into_the_moon_ends_at_the_impact_found_by_propagate():
    dyn = CR3BP()
    moon = np.array([1.0 - dyn.mu, 0.0, 0.0])
    state = np.r_[moon + [0.0, 0.05, 0.01], [0.02, -0.5, 0.0]]
    traj = dyn.dense_trajectory(state, 0.0, 2.0)
    prop = dyn.propagate(state, 0.0, 2.0)
    assert not traj.alive and traj.impact_body == int(prop.impact_body[0])
    assert traj.impact_time == prop.impact_time[0] == traj.t1
    np.testing.assert_array_equal(traj.states(traj.t1)[0], prop.final[0])
    mid = 0.5 * traj.t1
    np.testing.assert_allclose(traj.states(mid)[0], _reference(state, np.array([mid]))[0], rtol=0, atol=1e-9)


def test_times_outside_the_span_are_refused_with_the_span_named():
    traj = CR3BP().dense_trajectory(NRHO.state, 0.0, 0.5)
    with pytest.raises(StateError, match=r"outside.*\[0, 0.5\]|\[0, 0.5\].*outside"):
        traj.states([0.2, 0.7])


def test_more_than_one_state_is_refused():
    with pytest.raises(StateError, match="one state"):
        CR3BP().dense_trajectory(np.stack([NRHO.state, NRHO.state]), 0.0, 0.5)


def test_a_state_whose_derivative_overflows_the_step_heuristic_is_integrated():
    """At 1e144 LU with no velocity the rotating frame's acceleration is ~1e144 LU/TU^2: the
    starting step's derivative norm overflows, which had left a zero first step and a division
    by zero. Gravity is nothing there, so the object moves in a straight line in the inertial
    frame: in the rotating frame x = r (cos t + t sin t), y = r (t cos t - sin t)."""
    r, t = 2.6e144, 1.0
    x0 = np.array([r, 0.0, 0.0, 0.0, 0.0, 0.0])
    expected = r * np.array([np.cos(t) + t * np.sin(t), t * np.cos(t) - np.sin(t)])
    dyn = CR3BP()
    ensemble = dyn.propagate(np.stack([x0, NRHO.state]), 0.0, t).states[0]
    dense = dyn.dense_trajectory(x0, 0.0, t).states(np.array([t]))
    for got in (ensemble[0, :2], dense[0, :2]):
        assert np.allclose(got, expected, rtol=1e-9, atol=0.0)
