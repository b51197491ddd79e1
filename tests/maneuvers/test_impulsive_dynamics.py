"""ImpulsiveDynamics: a base model flown with impulsive burns, checked against independent
compositions (the base propagated to the burn, the dv added by hand, propagated on), central
differences, the two-body vis-viva energy change and the base's own dense output."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack import units
from cistrack.errors import ConfigError, StateError
from cistrack.interfaces.maneuvers import Impulse
from cistrack.plugins.dynamics.cr3bp import CR3BP
from cistrack.plugins.dynamics.twobody import TwoBody
from cistrack.propagation.impulses import MS_PER_VU, ImpulsiveDynamics, ImpulsiveTrajectory

NRHO = np.array([1.0221, 0.0, -0.1821508, 0.0, -0.10342725, 0.0])
T_B = 0.6                                    # TU, between apolune and perilune of the 9:2 NRHO
DV = np.array([1e-3, -2e-3, 5e-4])           # VU (about 1, 2, 0.5 m/s)


def _kick(x, dv):
    """States ``x`` (..., 6) with ``dv`` (3,) added to the velocity."""
    return x + np.concatenate([np.zeros(3), dv])


@pytest.fixture(scope="module")
def base():
    return CR3BP()


def _cloud(n: int = 5) -> np.ndarray:
    rng = np.random.default_rng(3)
    return NRHO + rng.normal(0.0, 1e-5, (n, 6))


def test_a_zero_impulse_gives_the_base_bit_for_bit(base):
    dyn = ImpulsiveDynamics(base, [Impulse(T_B, np.zeros(3), "nothing")])
    times = np.linspace(0.1, 1.4, 7)
    for states in (_cloud(5), _cloud(1)):
        got, want = dyn.propagate(states, 0.0, times), base.propagate(states, 0.0, times)
        assert np.array_equal(got.states, want.states)
        assert np.array_equal(got.alive, want.alive)
    got = dyn.dense_trajectory(NRHO, 0.0, 1.4).states(times)
    assert np.array_equal(got, base.dense_trajectory(NRHO, 0.0, 1.4).states(times))
    xs, stms = dyn.propagate_with_stm(NRHO, 0.0, times)
    xb, stmb = base.propagate_with_stm(NRHO, 0.0, times)
    assert np.array_equal(xs, xb) and np.array_equal(stms, stmb)


def test_forward_equals_the_base_to_the_burn_plus_dv_then_on(base):
    states = _cloud(5)
    dyn = ImpulsiveDynamics(base, [Impulse(T_B, DV, "b")])
    before, after = np.array([0.2, 0.4]), np.array([0.9, 1.3])
    got = dyn.propagate(states, 0.0, np.concatenate([before, [T_B], after]))
    first = base.propagate(states, 0.0, np.concatenate([before, [T_B]]))
    on = base.propagate(_kick(first.final, DV), T_B, after)
    np.testing.assert_allclose(got.states[:3], first.states, rtol=0, atol=1e-12)
    assert np.array_equal(got.states[2], first.final)          # at t_b: the pre-burn state
    np.testing.assert_allclose(got.states[3:], on.states, rtol=0, atol=1e-11)
    assert got.alive.all() and np.all(got.impact_body == -1) and np.all(np.isinf(got.impact_time))


def test_a_burn_at_the_start_is_applied_one_at_the_end_is_not(base):
    dyn = ImpulsiveDynamics(base, [Impulse(T_B, DV)])
    at_start = dyn.propagate(NRHO, T_B, [T_B, 1.0])
    assert np.array_equal(at_start.states[0, 0], NRHO)          # the state at t_b is pre-burn
    np.testing.assert_allclose(at_start.states[1, 0], base.propagate(_kick(NRHO, DV), T_B, 1.0).final[0], atol=1e-12)
    at_end = dyn.propagate(NRHO, 0.0, T_B)
    np.testing.assert_allclose(at_end.final[0], base.propagate(NRHO, 0.0, T_B).final[0], atol=1e-12)


def test_backward_subtracts_the_dv_and_returns_to_the_start(base):
    dyn = ImpulsiveDynamics(base, [Impulse(T_B, DV)])
    t_end = 1.2
    x_end = dyn.propagate(NRHO, 0.0, t_end).final[0]
    back = dyn.propagate(x_end, t_end, [0.9, T_B, 0.3, 0.0])
    # by hand: the base back to the burn, the dv taken off, the base back on
    to_burn = base.propagate(x_end, t_end, [0.9, T_B])
    pre = _kick(to_burn.final[0], -DV)
    rest = base.propagate(pre, T_B, [0.3, 0.0])
    np.testing.assert_allclose(back.states[0, 0], to_burn.states[0, 0], atol=1e-12)
    np.testing.assert_allclose(back.states[1, 0], pre, atol=1e-12)   # at t_b: the pre-burn state again
    np.testing.assert_allclose(back.states[2:, 0], rest.states[:, 0], atol=1e-12)
    np.testing.assert_allclose(back.final[0], NRHO, atol=1e-9)


def test_the_stm_matches_central_differences_across_the_burn(base):
    dyn = ImpulsiveDynamics(base, [Impulse(T_B, DV), Impulse(1.0, -DV)])
    times = np.array([0.3, 0.8, 1.3])
    xs, stms = dyn.propagate_with_stm(NRHO, 0.0, times)
    np.testing.assert_allclose(xs, dyn.propagate(NRHO, 0.0, times).states[:, 0], atol=1e-10)
    h = 1e-6
    pert = np.concatenate([NRHO + h * np.eye(6), NRHO - h * np.eye(6)])
    p = dyn.propagate(pert, 0.0, times).states
    fd = np.transpose((p[:, :6] - p[:, 6:]) / (2 * h), (0, 2, 1))
    scale = np.abs(fd).max(axis=(1, 2))[:, None, None]
    assert np.all(np.abs(stms - fd) <= 1e-5 * scale)


def test_backward_stm_inverts_the_forward_one(base):
    dyn = ImpulsiveDynamics(base, [Impulse(T_B, DV)])
    x1, phi = dyn.propagate_with_stm(NRHO, 0.0, 1.2)
    x0, psi = dyn.propagate_with_stm(x1[0], 1.2, 0.0)
    np.testing.assert_allclose(x0[0], NRHO, atol=1e-9)
    np.testing.assert_allclose(psi[0] @ phi[0], np.eye(6), atol=1e-6)


def test_two_body_burn_changes_the_energy_by_v_dot_dv_plus_half_dv_squared():
    tb = TwoBody()
    gm = tb.gm
    r = 0.1                                                   # LU (38,440 km), circular
    x0 = np.array([r, 0, 0, 0, np.sqrt(gm / r) * 0.9, 0.1 * np.sqrt(gm / r)])
    dv = np.array([0.004, 0.012, -0.003])                    # VU
    t_b = 0.05
    dyn = ImpulsiveDynamics(tb, [Impulse(t_b, dv)])
    x_b = tb.kepler(x0[None], t_b)[0]                         # closed form: the pre-burn state

    def energy(s):
        return 0.5 * np.sum(s[..., 3:] ** 2, axis=-1) - gm / np.linalg.norm(s[..., :3], axis=-1)

    out = dyn.propagate(x0, 0.0, [0.02, 0.08, 0.2]).states[:, 0]
    assert abs(energy(out[0]) - energy(x0)) < 1e-11
    want = energy(x0) + x_b[3:] @ dv + 0.5 * dv @ dv
    np.testing.assert_allclose(energy(out[1:]), want, rtol=1e-10)
    after = tb.kepler((x_b + np.concatenate([np.zeros(3), dv]))[None], 0.2 - t_b)[0]
    np.testing.assert_allclose(out[2], after, atol=1e-10)


def test_dense_output_matches_propagate_through_burns(base):
    dyn = ImpulsiveDynamics(base, [Impulse(T_B, DV), Impulse(1.1, -0.5 * DV)])
    traj = dyn.dense_trajectory(NRHO, 0.0, 1.5)
    assert isinstance(traj, ImpulsiveTrajectory)
    assert traj.t1 == 1.5 and traj.alive and traj.impact_body == -1 and np.isinf(traj.impact_time)
    ts = np.sort(np.random.default_rng(7).uniform(0.0, 1.5, 40))
    ts = np.concatenate([ts, [T_B, 1.1, 1.5]])
    want = dyn.propagate(NRHO, 0.0, np.sort(ts)).states[:, 0]
    np.testing.assert_allclose(traj.states(np.sort(ts)), want, atol=1e-9)
    np.testing.assert_allclose(traj.states(T_B)[0], base.propagate(NRHO, 0.0, T_B).final[0], atol=1e-11)
    with pytest.raises(StateError):
        traj.states(1.6)


def test_dense_output_backward(base):
    dyn = ImpulsiveDynamics(base, [Impulse(T_B, DV)])
    x_end = dyn.propagate(NRHO, 0.0, 1.2).final[0]
    traj = dyn.dense_trajectory(x_end, 1.2, 0.0)
    ts = np.array([1.0, T_B, 0.4, 0.0])
    np.testing.assert_allclose(traj.states(ts), dyn.propagate(x_end, 1.2, ts).states[:, 0], atol=1e-9)


def test_a_particle_that_dies_before_the_burn_stays_dead():
    tb = TwoBody()
    falling = np.array([0.05, 0.0, 0.0, -0.3, 0.0, 0.0])     # straight down onto the Earth
    r = 0.1
    circular = np.array([r, 0.0, 0.0, 0.0, np.sqrt(tb.gm / r), 0.0])
    dv = np.array([0.0, 0.01, 0.0])
    dyn = ImpulsiveDynamics(tb, [Impulse(0.2, dv)])
    p = dyn.propagate(np.stack([falling, circular]), 0.0, [0.1, 0.3, 0.5])
    assert list(p.alive) == [False, True]
    assert p.impact_body[0] == 0 and p.impact_time[0] < 0.1
    assert np.array_equal(p.states[0, 0], p.states[2, 0])      # frozen at the impact
    want = tb.kepler((tb.kepler(circular[None], 0.2)[0] + np.r_[0, 0, 0, dv])[None], 0.3)[0]
    np.testing.assert_allclose(p.states[2, 1], want, atol=1e-10)


def test_a_particle_that_dies_after_the_burn_is_reported_there():
    tb = TwoBody()
    r = 0.1
    x0 = np.array([r, 0.0, 0.0, 0.0, np.sqrt(tb.gm / r), 0.0])
    v_b = tb.kepler(x0[None], 0.05)[0, 3:]
    dyn = ImpulsiveDynamics(tb, [Impulse(0.05, -0.99 * v_b)])      # nearly stopped: it falls in
    p = dyn.propagate(np.stack([x0] * 2), 0.0, [0.04, 2.0])
    assert not p.alive.any() and np.all(p.impact_time > 0.05) and np.all(p.impact_body == 0)
    traj = dyn.dense_trajectory(x0, 0.0, 2.0)
    assert not traj.alive and traj.impact_time == pytest.approx(p.impact_time[0], abs=1e-9)


def test_the_partial_of_a_measurement_wrt_a_burn_component_is_finite_and_linear(base):
    dyn = ImpulsiveDynamics(base, [Impulse(T_B, DV, "b")])
    t_meas = 1.0
    earth = np.array([-base.mu, 0.0, 0.0])

    def angles(d):
        x = d.propagate(NRHO, 0.0, t_meas).final[0, :3] - earth
        return np.array([np.arctan2(x[1], x[0]), np.arcsin(x[2] / np.linalg.norm(x))])

    def partial(h):
        v = dyn.parameter("delta_v_0_x_ms")
        return (angles(dyn.with_parameters(delta_v_0_x_ms=v + h))
                - angles(dyn.with_parameters(delta_v_0_x_ms=v - h))) / (2 * h)

    coarse, fine = partial(1e-3), partial(1e-4)
    assert np.all(np.isfinite(coarse)) and np.all(np.abs(coarse) > 0)
    np.testing.assert_allclose(coarse, fine, rtol=1e-3)
    # the same partial through the chained STM: d x(t) / d dv_x = Phi(t, t_b)[:, 3] per m/s
    _, phi = base.propagate_with_stm(_kick(dyn.propagate(NRHO, 0.0, T_B).final[0], DV), T_B, t_meas)
    dx = phi[0][:3, 3] / MS_PER_VU
    x = dyn.propagate(NRHO, 0.0, t_meas).final[0, :3] - earth
    rho2 = x[0] ** 2 + x[1] ** 2
    d_ra = (x[0] * dx[1] - x[1] * dx[0]) / rho2
    np.testing.assert_allclose(coarse[0], d_ra, rtol=1e-4)


def test_solve_for_parameters_names_values_and_copies(base):
    dyn = ImpulsiveDynamics(base, [Impulse(1.0, DV, "second"), Impulse(T_B, 2 * DV, "first")])
    assert [imp.label for imp in dyn.impulses] == ["first", "second"]   # in time order
    assert dyn.solve_for_parameters == ("delta_v_0_x_ms", "delta_v_0_y_ms", "delta_v_0_z_ms",
                                        "delta_v_1_x_ms", "delta_v_1_y_ms", "delta_v_1_z_ms")
    assert dyn.parameter("delta_v_1_y_ms") == pytest.approx(DV[1] * units.VU_KMS * 1000)
    new = dyn.with_parameters(delta_v_0_z_ms=0.25)
    assert isinstance(new, ImpulsiveDynamics) and new is not dyn
    assert new.parameter("delta_v_0_z_ms") == pytest.approx(0.25)
    assert dyn.parameter("delta_v_0_z_ms") == pytest.approx(2 * DV[2] * units.VU_KMS * 1000)
    assert new.impulses[0].t == T_B and new.impulses[0].label == "first"
    for bad in ("delta_v_2_x_ms", "delta_v_0_w_ms", "mu", "delta_v_00_x_ms"):
        with pytest.raises(StateError, match="no solve-for parameter"):
            dyn.parameter(bad)
        with pytest.raises(StateError, match="no solve-for parameter"):
            dyn.with_parameters(**{bad: 1.0})
    with pytest.raises(StateError, match="finite"):
        dyn.with_parameters(delta_v_0_x_ms=float("nan"))


class _MuCR3BP(CR3BP):
    """A CR3BP offering its mass ratio as a solve-for parameter (for the pass-through)."""

    solve_for_parameters = ("mu",)

    def parameter(self, name):
        return self.mu

    def with_parameters(self, **values):
        return _MuCR3BP(mu=values["mu"])


def test_the_base_parameters_pass_through():
    dyn = ImpulsiveDynamics(_MuCR3BP(), [Impulse(T_B, DV)])
    assert dyn.solve_for_parameters[0] == "mu" and len(dyn.solve_for_parameters) == 4
    new = dyn.with_parameters(mu=0.0125, delta_v_0_x_ms=3.0)
    assert new.base.mu == 0.0125 and new.parameter("mu") == 0.0125
    assert new.parameter("delta_v_0_x_ms") == pytest.approx(3.0)
    assert dyn.base.mu != 0.0125


def test_everything_else_is_the_base(registry):
    base = registry.create("dynamics", "cr3bp")
    dyn = ImpulsiveDynamics(base, [Impulse(T_B, DV)])
    assert dyn.bodies is base.bodies or [b.name for b in dyn.bodies] == [b.name for b in base.bodies]
    assert [b.radius for b in dyn.primaries] == [b.radius for b in base.primaries]
    assert dyn.mu == base.mu and dyn.rtol == base.rtol and dyn.registry_name == "cr3bp"
    assert dyn.carries_steps is False
    np.testing.assert_array_equal(dyn.derivatives(0.3, _cloud(2)), base.derivatives(0.3, _cloud(2)))
    assert "impulse" in dyn._label()


def test_nested_impulsive_models_flatten(base):
    inner = ImpulsiveDynamics(base, [Impulse(1.0, DV)])
    outer = ImpulsiveDynamics(inner, [Impulse(T_B, DV)])
    assert outer.base is base and [i.t for i in outer.impulses] == [T_B, 1.0]


def test_malformed_input_is_refused_with_a_clear_error(base):
    with pytest.raises(ConfigError, match="Dynamics"):
        ImpulsiveDynamics("cr3bp", [])
    with pytest.raises(ConfigError, match="Impulse"):
        ImpulsiveDynamics(base, [(0.5, DV)])
    with pytest.raises(ConfigError, match="sequence"):
        ImpulsiveDynamics(base, Impulse(0.5, DV))
    dyn = ImpulsiveDynamics(base, [Impulse(T_B, DV)])
    with pytest.raises(StateError, match=r"\(N, 6\)"):
        dyn.propagate(np.zeros((2, 5)), 0.0, 1.0)
    with pytest.raises(StateError, match="NaN"):
        dyn.propagate(np.full(6, np.nan), 0.0, 1.0)
    with pytest.raises(StateError, match="monotonic"):
        dyn.propagate(NRHO, 0.0, [1.0, 0.5])
    with pytest.raises(StateError, match="no output times"):
        dyn.propagate(NRHO, 0.0, [])
    with pytest.raises(StateError):
        dyn.propagate_with_stm(np.zeros(5), 0.0, 1.0)
    with pytest.raises(StateError, match="one state"):
        dyn.dense_trajectory(np.stack([NRHO, NRHO]), 0.0, 1.0)


def test_no_dense_trajectory_without_the_base_one(base):
    class Plain:
        def propagate(self, states, t0, times):
            return base.propagate(states, t0, times)

        def derivatives(self, t, states):
            return base.derivatives(t, states)

    dyn = ImpulsiveDynamics(Plain(), [Impulse(T_B, DV)])
    assert getattr(dyn, "dense_trajectory", None) is None
    np.testing.assert_allclose(dyn.propagate(NRHO, 0.0, 1.0).final,
                               ImpulsiveDynamics(base, [Impulse(T_B, DV)]).propagate(NRHO, 0.0, 1.0).final, atol=1e-12)


def test_the_fit_machinery_takes_the_burn_components_as_solve_for_parameters(base):
    """cistrack.least_squares' SolveFor: initial values, a model per value, partials by its steps."""
    import pickle

    from cistrack.least_squares.solve_for_parameters import solve_for

    dyn = ImpulsiveDynamics(base, [Impulse(T_B, DV, "b")])
    sf = solve_for(dyn, ("delta_v_0_x_ms", "delta_v_0_z_ms"))
    np.testing.assert_allclose(sf.initial(), [DV[0] * MS_PER_VU, DV[2] * MS_PER_VU])
    jac = sf.partials(lambda d: d.propagate(NRHO, 0.0, [0.9, 1.2]).states[:, 0, :3], sf.initial())
    _, phi = base.propagate_with_stm(_kick(dyn.propagate(NRHO, 0.0, T_B).final[0], DV), T_B, [0.9, 1.2])
    np.testing.assert_allclose(jac, phi[:, :3, [3, 5]] / MS_PER_VU, rtol=1e-4, atol=1e-12)
    again = pickle.loads(pickle.dumps(dyn))
    assert np.array_equal(again.propagate(NRHO, 0.0, 1.0).final, dyn.propagate(NRHO, 0.0, 1.0).final)
