"""Ephemeris dynamics (Earth, Moon, Sun from DE421): agrees with an independent scipy integration
reading DE421 through jplephem, finds impacts on the moving Moon and the Earth, transforms its
derivatives correctly into the real rotating frame, and passes the conformance suite."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack import units
from cistrack.astro.ephemeris import DAY_S
from cistrack.errors import StateError
from cistrack.plugins.dynamics.orbit_catalog import get_orbit
from cistrack.plugins.dynamics.ephemeris import EphemerisDynamics
from cistrack.testing import check_plugin

from . import reference_ephemeris as ref

EPOCH = "2026-01-01T00:00:00Z"


@pytest.fixture(scope="module")
def dyn():
    return EphemerisDynamics(epoch=EPOCH)


def _nrho_state(dyn) -> np.ndarray:
    """The CR3BP 9:2 NRHO apolune state placed in the real frame with the pulsating scaling."""
    orbit = get_orbit("nrho-9-2")
    g = dyn.frame.pulsating_to_gcrs(np.asarray(orbit.state, float), 0.0)
    return dyn.frame.gcrs_to_synodic(g, 0.0)


def test_passes_the_conformance_suite(dyn):
    report = check_plugin(dyn)
    assert report.passed, str(report)


def test_one_nrho_revolution_agrees_with_an_independent_integration_to_1_m(dyn):
    x0 = _nrho_state(dyn)
    period = get_orbit("nrho-9-2").period
    times = np.linspace(0.0, period, 9)[1:]
    prop = dyn.propagate(x0[None], 0.0, times)
    assert prop.alive[0]
    got = np.array([dyn.frame.synodic_to_gcrs(prop.states[k, 0], t) for k, t in enumerate(times)])
    jd0 = dyn.frame.epoch_tdb
    want = ref.propagate_km(dyn.frame.synodic_to_gcrs(x0, 0.0), jd0, times * units.TU_S)
    err_m = np.linalg.norm(got[:, :3] - want[:, :3], axis=1) * 1000.0
    assert err_m.max() < 1.0, err_m


def test_without_the_sun_it_still_agrees_with_the_reference(dyn):
    no_sun = EphemerisDynamics(epoch=EPOCH, sun=False)
    x0 = _nrho_state(dyn)
    t = 0.5
    got = no_sun.frame.synodic_to_gcrs(no_sun.propagate(x0[None], 0.0, t).final[0], t)
    want = ref.propagate_km(no_sun.frame.synodic_to_gcrs(x0, 0.0), no_sun.frame.epoch_tdb,
                            np.array([t * units.TU_S]), sun=False)[0]
    assert np.linalg.norm(got[:3] - want[:3]) * 1000.0 < 1.0


def test_the_sun_moves_an_nrho_by_far_more_than_the_tolerance(dyn):
    no_sun = EphemerisDynamics(epoch=EPOCH, sun=False)
    x0 = _nrho_state(dyn)[None]
    a = dyn.propagate(x0, 0.0, 1.5).final
    b = no_sun.propagate(x0, 0.0, 1.5).final
    assert units.lu_to_km(np.linalg.norm(a[0, :3] - b[0, :3])) > 10.0


def test_synodic_derivatives_match_finite_differences_of_propagation(dyn):
    x0 = _nrho_state(dyn)[None]
    h = 1e-5
    for t in (0.0, 0.7):
        xt = dyn.propagate(x0, 0.0, t).final if t else x0
        plus = dyn.propagate(xt, t, t + h).final
        minus = dyn.propagate(xt, t, t - h).final
        fd = (plus - minus) / (2.0 * h)
        d = dyn.derivatives(t, xt)
        np.testing.assert_allclose(d, fd, rtol=1e-6, atol=1e-7)  # O(h^2) differences


def _falling_onto(dyn, body: str) -> np.ndarray:
    """GCRS state 2000 km above ``body``'s surface at t = 0, falling straight at 2 km/s."""
    frame = dyn.frame
    jd1, jd2 = frame.epoch_tdb
    centre = np.zeros(6)
    radius = dyn.earth_radius_km
    if body == "Moon":
        r, v = frame.ephemeris.moon(jd1, jd2)
        centre = np.concatenate([r, v])
        radius = dyn.moon_radius_km
    u = np.array([0.3, -0.5, 0.81])
    u /= np.linalg.norm(u)
    return centre + np.concatenate([(radius + 2000.0) * u, -2.0 * u])


@pytest.mark.parametrize("body", ["Earth", "Moon"])
def test_impact_time_and_place_match_an_independent_event_search(dyn, body):
    from scipy.integrate import solve_ivp

    g0 = _falling_onto(dyn, body)
    x0 = dyn.frame.gcrs_to_synodic(g0, 0.0)
    t_end = float(units.hours_to_tu(2.0))
    prop = dyn.propagate(np.stack([x0, _nrho_state(dyn)]), 0.0, [0.5 * t_end, t_end])
    index = [b.name for b in dyn.bodies].index(body)
    assert not prop.alive[0] and prop.alive[1]
    assert prop.impact_body[0] == index

    jd0 = dyn.frame.epoch_tdb
    radius = dyn.moon_radius_km if body == "Moon" else dyn.earth_radius_km

    def gap(t, y):
        c = ref.moon_sun(jd0[0], jd0[1] + t / ref.DAY)[0] if body == "Moon" else np.zeros(3)
        return np.linalg.norm(y[:3] - c) - radius
    gap.terminal = True
    sol = solve_ivp(ref.rhs(jd0), (0.0, 7200.0), g0, method="DOP853", rtol=1e-13, atol=1e-9,
                    events=gap)
    t_hit = sol.t_events[0][0]
    assert abs(prop.impact_time[0] * units.TU_S - t_hit) < 1e-3  # seconds
    # the frozen state is on the surface, at the impact time, in the rotating frame
    g_hit = dyn.frame.synodic_to_gcrs(prop.states[-1, 0], prop.impact_time[0])
    assert abs(gap(t_hit, g_hit)) < 1e-3  # km
    np.testing.assert_allclose(prop.states[0, 0], prop.states[1, 0])


def test_j2_acceleration_is_the_gradient_of_the_j2_potential():
    dyn = EphemerisDynamics(epoch=EPOCH, j2=True, sun=False)
    base = EphemerisDynamics(epoch=EPOCH, j2=False, sun=False)
    p = dyn.params_vector()
    gm, j2, re = p[0], p[3], p[4]
    k = p[5:8]
    assert abs(np.linalg.norm(k) - 1.0) < 1e-12 and k[2] > 0.9999

    def potential(r):
        rn = np.linalg.norm(r)
        s = np.dot(r, k) / rn
        return gm / rn * j2 * (re / rn) ** 2 * 0.5 * (3.0 * s * s - 1.0)  # J2 part of V

    r = np.array([0.0301, -0.012, 0.021])  # ~15,000 km
    y = np.concatenate([r, [0.0, 0.0, 0.0]])[None]
    a = (dyn.inertial_derivatives(0.0, y) - base.inertial_derivatives(0.0, y))[0, 3:]
    h = 1e-7
    grad = np.array([(potential(r + h * e) - potential(r - h * e)) / (2 * h) for e in np.eye(3)])
    np.testing.assert_allclose(a, -grad, rtol=1e-6)


def test_solar_radiation_pressure_pushes_away_from_the_sun_with_the_right_magnitude():
    amr, cr = 0.02, 1.5  # m^2/kg
    dyn = EphemerisDynamics(epoch=EPOCH, srp_area_to_mass_m2_kg=amr, srp_reflectivity=cr)
    base = EphemerisDynamics(epoch=EPOCH)
    y = np.array([[0.5, 0.2, -0.1, 0.0, 0.0, 0.0]])
    a = (dyn.inertial_derivatives(0.0, y) - base.inertial_derivatives(0.0, y))[0, 3:]
    a_kms2 = a * units.LU_KM / units.TU_S ** 2
    jd0 = dyn.frame.epoch_tdb
    sun = ref.moon_sun(*jd0)[1]
    away = y[0, :3] * units.LU_KM - sun
    dist_au = np.linalg.norm(away) / dyn.frame.ephemeris.au_km
    expect = cr * amr * 4.56e-6 / 1000.0 / dist_au ** 2 * away / np.linalg.norm(away)
    np.testing.assert_allclose(a_kms2, expect, rtol=1e-10)


def test_bad_parameters_are_refused_by_name():
    from cistrack.errors import CistrackError

    with pytest.raises(CistrackError, match="epoch"):
        EphemerisDynamics(epoch="yesterday")
    with pytest.raises(CistrackError, match="sun"):
        EphemerisDynamics(sun="yes")
    with pytest.raises(CistrackError, match="srp_reflectivity"):
        EphemerisDynamics(srp_reflectivity=3.0)


def test_epochs_outside_de421_are_refused():
    from cistrack.errors import CistrackError

    with pytest.raises(CistrackError, match="DE421"):
        EphemerisDynamics(epoch="2060-01-01T00:00:00Z")


def test_kernel_moon_and_sun_reproduce_de421_within_a_millimetre_and_a_centimetre(dyn):
    from cistrack.plugins.dynamics.ephemeris_rhs import bodies_position as evaluate

    params = dyn.params_vector()
    ts = np.linspace(-30.0, 30.0, 601) * DAY_S / units.TU_S
    got = np.array([evaluate(params, t) for t in ts]) * units.LU_KM
    jd1, jd2 = dyn.frame.epoch_tdb
    moon, _ = dyn.frame.ephemeris.moon(jd1, jd2 + ts * units.TU_S / DAY_S)
    sun, _ = dyn.frame.ephemeris.sun(jd1, jd2 + ts * units.TU_S / DAY_S)
    sun_got = got[:, 3:] + dyn.frame.ephemeris.earth_share * got[:, :3]
    assert np.max(np.abs(got[:, :3] - moon)) < 1e-6  # km (measured 3.3e-7)
    assert np.max(np.abs(sun_got - sun)) < 1e-5  # km (measured 9e-6)


def test_a_scenario_hands_its_epoch_to_the_ephemeris_dynamics(registry):
    import tomllib

    from cistrack.scenario.loading import builtin_scenario_path, parse_scenario

    data = tomllib.loads(builtin_scenario_path("quick").read_text())
    data["epoch"] = "2027-03-04T05:06:07Z"
    data["dynamics"] = {"name": "ephemeris", "j2": True}
    data["truth"]["dynamics"] = {"name": "ephemeris"}
    sc = parse_scenario(data, registry=registry)
    built = sc.components["dynamics"].build(registry)
    assert built.epoch.startswith("2027-03-04T05:06:07") and built.j2
    assert sc.truth_dynamics.build(registry).epoch.startswith("2027-03-04T05:06:07")


def test_records_needing_more_powers_than_the_kernel_evaluates_are_refused(dyn):
    from cistrack.plugins.dynamics.ephemeris_rhs import NCOEF, pack_params

    eph, origin = dyn.frame.ephemeris, dyn.frame.epoch_tdb
    moon = eph.series("moon", origin, 0.0, 10 * DAY_S)
    sun = eph.series("sun", origin, 0.0, 10 * DAY_S)
    with pytest.raises(ValueError, match=f"need 11 powers.*NCOEF = {NCOEF}"):
        pack_params(np.zeros(12), moon, sun, units.LU_KM, units.TU_S, record_s=86_400.0)
    assert pack_params(np.zeros(12), moon, sun, units.LU_KM, units.TU_S)[15] == NCOEF


def test_a_sun_series_needing_more_powers_than_the_kernel_evaluates_is_refused(dyn):
    from cistrack.plugins.dynamics.ephemeris_rhs import NSUN, pack_params

    eph, origin = dyn.frame.ephemeris, dyn.frame.epoch_tdb
    moon = eph.series("moon", origin, 0.0, 10 * DAY_S)
    sun = eph.series("sun", origin, 0.0, 10 * DAY_S)
    with pytest.raises(ValueError, match=f"Sun's series.*NSUN = {NSUN}"):
        pack_params(np.zeros(12), moon, sun, units.LU_KM, units.TU_S, sun_drop_below_km=1e-12)


def test_the_sun_series_of_the_default_records_has_no_power_beyond_the_evaluated_ones(dyn):
    from cistrack.plugins.dynamics.ephemeris_rhs import HEADER_SIZE, NCOEF, NSUN, SERIES_HDR

    p = dyn.params_vector()
    joint = p[HEADER_SIZE:].reshape(int(p[SERIES_HDR + 2]), NCOEF, 6)
    assert np.all(joint[:, NSUN:, 3:] == 0.0) and np.all(joint[:, NSUN - 1, 3:] != 0.0)


@pytest.mark.parametrize("sun", [True, False])
def test_the_point_mass_right_hand_side_gives_the_general_ones_numbers_bit_for_bit(sun):
    from cistrack.plugins.dynamics.ephemeris_point_mass_rhs import ephemeris_point_mass_rhs
    from cistrack.plugins.dynamics.ephemeris_rhs import ephemeris_rhs

    model = EphemerisDynamics(epoch=EPOCH, sun=sun)
    p = model.params_vector()
    rng = np.random.default_rng(3)
    states = model.to_inertial(_nrho_state(model) + rng.normal(size=(200, 6)) * 0.05, 0.0)
    times = rng.uniform(-5.0, 5.0, size=200)
    for t, y in zip(times, states):
        a, b = np.empty(6), np.empty(6)
        ephemeris_rhs(t, y, p, a)
        ephemeris_point_mass_rhs(t, y, p, b)
        assert np.array_equal(a, b)


def test_the_model_integrates_the_point_mass_right_hand_side_unless_j2_or_radiation_pressure_is_on():
    from cistrack.plugins.dynamics.ephemeris_point_mass_rhs import ephemeris_point_mass_rhs
    from cistrack.plugins.dynamics.ephemeris_rhs import ephemeris_rhs

    assert EphemerisDynamics(epoch=EPOCH)._rhs() is ephemeris_point_mass_rhs
    assert EphemerisDynamics(epoch=EPOCH, sun=False)._rhs() is ephemeris_point_mass_rhs
    assert EphemerisDynamics(epoch=EPOCH, j2=True)._rhs() is ephemeris_rhs
    assert EphemerisDynamics(epoch=EPOCH, srp_area_to_mass_m2_kg=0.01)._rhs() is ephemeris_rhs
    assert EphemerisDynamics(epoch=EPOCH, srp_area_to_mass_m2_kg=0.01, srp_reflectivity=0.0)._rhs() \
        is ephemeris_point_mass_rhs


def test_a_propagation_near_the_start_of_de421_runs_and_one_past_it_is_refused_naming_the_dates():
    early = EphemerisDynamics(epoch="1900-01-10T00:00:00Z", sun=False)  # DE421 starts 1899-12-04
    x = _nrho_state(early)[None]
    back = early.propagate(x, 0.0, -float(units.days_to_tu(5.0)))  # the body tables' padding stays inside DE421
    assert np.all(np.isfinite(back.states))
    with pytest.raises(StateError, match=r"1899-11-1\d.*leaves the DE421 ephemeris, which covers 1899-12-0\d"):
        early.propagate(x, 0.0, -float(units.days_to_tu(60.0)))
