"""CR3BP model: equations of motion, conservation, accuracy, backward propagation, impacts."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from cistrack import units
from cistrack.errors import ParameterError
from cistrack.plugins.dynamics.orbit_catalog import ORBITS
from cistrack.propagation import StateError
from cistrack.plugins.dynamics.cr3bp import CR3BP, jacobi_constant

PERIODIC = [name for name, o in ORBITS.items() if o.period is not None]


def _numpy_rhs(mu):
    """An independent (numpy, REFERENCE.md) statement of the CR3BP equations."""
    def f(t, s):
        x, y, z, vx, vy, vz = s
        r1 = np.sqrt((x + mu) ** 2 + y ** 2 + z ** 2)
        r2 = np.sqrt((x - 1 + mu) ** 2 + y ** 2 + z ** 2)
        ax = x + 2 * vy - (1 - mu) * (x + mu) / r1 ** 3 - mu * (x - 1 + mu) / r2 ** 3
        ay = y - 2 * vx - (1 - mu) * y / r1 ** 3 - mu * y / r2 ** 3
        az = -(1 - mu) * z / r1 ** 3 - mu * z / r2 ** 3
        return np.array([vx, vy, vz, ax, ay, az])
    return f


def _reference(state, t_end, mu):
    sol = solve_ivp(_numpy_rhs(mu), (0.0, t_end), state, method="DOP853", rtol=1e-13, atol=1e-15)
    return sol.y[:, -1]


def _cloud(orbit, n, rng, pos_km=10.0, vel_kms=1e-5):
    sig = np.r_[[pos_km / units.LU_KM] * 3, [vel_kms / units.VU_KMS] * 3]
    return orbit.state + rng.normal(size=(n, 6)) * sig


def test_derivatives_match_the_reference_equations_including_the_z_sign(rng):
    dyn = CR3BP()
    states = ORBITS["nrho-9-2"].state + rng.normal(scale=0.05, size=(20, 6))
    expected = np.array([_numpy_rhs(dyn.mu)(0.0, s) for s in states])
    np.testing.assert_allclose(dyn.derivatives(0.0, states), expected, rtol=1e-13, atol=1e-13)


@pytest.mark.parametrize("name", PERIODIC)
def test_jacobi_constant_drifts_at_most_1e_10_over_one_period_at_default_tolerance(name):
    orbit = ORBITS[name]
    dyn = CR3BP()
    times = np.linspace(0.0, orbit.period, 9)[1:]
    prop = dyn.propagate(orbit.state, 0.0, times)
    c0 = dyn.jacobi(orbit.state[None])[0]
    drift = np.abs(dyn.jacobi(prop.states[:, 0]) - c0)
    assert drift.max() <= 1e-10


@pytest.mark.parametrize("name", PERIODIC)
def test_catalog_orbit_closes_after_one_period(name):
    orbit = ORBITS[name]
    final = CR3BP().propagate(orbit.state, 0.0, orbit.period, rtol=1e-13, atol=1e-14).final[0]
    assert np.max(np.abs(final[:3] - orbit.state[:3])) <= 1e-9


def test_default_tolerance_meets_1e_9_after_one_nrho_period_against_a_1e_13_reference(rng):
    orbit = ORBITS["nrho-9-2"]
    states = _cloud(orbit, 8, rng)
    prop = CR3BP().propagate(states, 0.0, orbit.period)
    for i, s in enumerate(states):
        ref = _reference(s, orbit.period, orbit.mu)
        assert np.max(np.abs(prop.final[i, :3] - ref[:3])) <= 1e-9


def test_ensemble_equals_per_particle_scipy_dop853_at_tight_tolerance(rng):
    orbit = ORBITS["nrho-9-2"]
    states = _cloud(orbit, 6, rng, pos_km=100.0, vel_kms=1e-3)
    times = np.array([0.3, 0.9, orbit.period])
    prop = CR3BP().propagate(states, 0.0, times)
    for i, s in enumerate(states):
        sol = solve_ivp(_numpy_rhs(orbit.mu), (0.0, times[-1]), s, method="DOP853",
                        rtol=1e-13, atol=1e-15, t_eval=times)
        assert np.max(np.abs(prop.states[:, i, :] - sol.y.T)) <= 1e-9


def test_one_call_with_many_output_times_equals_separate_calls(rng):
    orbit = ORBITS["dro-2-1"]
    dyn = CR3BP(rtol=1e-12, atol=1e-13)
    states = _cloud(orbit, 4, rng)
    times = np.linspace(0.1, 2.0, 20)
    many = dyn.propagate(states, 0.0, times)
    for k in (0, 7, 19):
        single = dyn.propagate(states, 0.0, times[k]).final
        np.testing.assert_allclose(many.states[k], single, atol=1e-10)


def test_backward_propagation_returns_to_the_initial_states(rng):
    orbit = ORBITS["nrho-9-2"]
    dyn = CR3BP(rtol=1e-12, atol=1e-13)
    states = _cloud(orbit, 16, rng)
    fwd = dyn.propagate(states, 0.0, 0.7).final
    back = dyn.propagate(fwd, 0.7, [0.3, 0.0])
    assert np.max(np.abs(back.final - states)) <= 1e-9


def test_backward_propagation_agrees_with_scipy_backward(rng):
    orbit = ORBITS["nrho-3-1"]
    state = orbit.state
    prop = CR3BP().propagate(state, 0.0, -1.0).final[0]
    sol = solve_ivp(_numpy_rhs(orbit.mu), (0.0, -1.0), state, method="DOP853", rtol=1e-13, atol=1e-15)
    assert np.max(np.abs(prop - sol.y[:, -1])) <= 1e-9


def test_particle_aimed_at_the_moon_is_removed_and_counted_without_nan():
    dyn = CR3BP()
    mu = dyn.mu
    moon = np.array([1.0 - mu, 0.0, 0.0])
    start = moon + np.array([0.0, 0.05, 0.0])          # 19,220 km from the Moon
    aimed = np.r_[start, [0.0, -0.6, 0.0]]              # straight at it
    safe = ORBITS["dro-2-1"].state
    states = np.array([aimed, safe, aimed + [0, 0, 0, 0.001, 0, 0]])
    prop = dyn.propagate(states, 0.0, np.linspace(0.05, 1.0, 6))
    assert np.all(np.isfinite(prop.states))
    assert prop.alive.tolist() == [False, True, False]
    names = [b.name for b in dyn.bodies]
    assert prop.impact_counts(dyn.bodies) == {"Earth": 0, "Moon": 2}
    assert prop.impact_body.tolist() == [names.index("Moon"), -1, names.index("Moon")]
    assert np.all(np.isfinite(prop.impact_time[[0, 2]])) and np.isinf(prop.impact_time[1])


def test_impact_state_lies_on_the_surface_at_the_impact_time():
    dyn = CR3BP()
    moon = np.array([1.0 - dyn.mu, 0.0, 0.0])
    state = np.r_[moon + [0.0, 0.05, 0.01], [0.02, -0.5, 0.0]]
    prop = dyn.propagate(state, 0.0, 2.0)
    radius = dyn.bodies[1].radius
    assert not prop.alive[0]
    assert abs(np.linalg.norm(prop.final[0, :3] - moon) - radius) <= 1e-12
    # the frozen state is the trajectory's state at impact_time
    at_impact = _reference(state, prop.impact_time[0], dyn.mu)
    assert np.max(np.abs(at_impact - prop.final[0])) <= 1e-9


def test_particle_starting_inside_the_earth_is_flagged_at_t0():
    dyn = CR3BP()
    state = np.array([[-dyn.mu + 1e-3, 0, 0, 0, 0.1, 0]])
    prop = dyn.propagate(state, 0.0, 1.0)
    assert not prop.alive[0] and prop.impact_time[0] == 0.0
    np.testing.assert_array_equal(prop.final, state)


def test_jacobi_method_matches_the_formula():
    s = ORBITS["l2-lyapunov"].state[None]
    x, vy = s[0, 0], s[0, 4]
    mu = 1.2150582e-2
    expected = x * x + 2 * (1 - mu) / abs(x + mu) + 2 * mu / abs(x - 1 + mu) - vy * vy
    assert CR3BP().jacobi(s)[0] == pytest.approx(expected, rel=1e-14)
    assert jacobi_constant(s)[0] == pytest.approx(expected, rel=1e-14)


def test_states_with_nan_are_rejected_with_a_clear_error():
    with pytest.raises(StateError, match="NaN"):
        CR3BP().propagate(np.full((2, 6), np.nan), 0.0, 1.0)


def test_wrong_state_shape_is_rejected():
    with pytest.raises(StateError, match=r"\(N, 6\)"):
        CR3BP().propagate(np.zeros((3, 4)), 0.0, 1.0)


def test_output_times_on_both_sides_of_t0_are_rejected():
    with pytest.raises(StateError, match="monotonic"):
        CR3BP().propagate(ORBITS["dro-2-1"].state, 0.0, [0.5, -0.5])


def test_invalid_mass_ratio_is_a_parameter_error():
    with pytest.raises(ParameterError, match="mu"):
        CR3BP(mu=0.7)


def test_cr3bp_is_registered_and_picklable(registry):
    import pickle
    dyn = registry.create("dynamics", "cr3bp", mu=0.0121505856)
    clone = pickle.loads(pickle.dumps(dyn))
    assert clone.get_params() == dyn.get_params()
