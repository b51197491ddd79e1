"""The space telescope: where its observer is, what it measures besides angles, how a scenario
builds it, and its refusals."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.errors import ConfigError, ParameterError
from cistrack.evaluation.information_bound import measurement_jacobian
from cistrack.plugins.dynamics.orbit_catalog import ORBITS
from cistrack.plugins.sensors.space_frames import IdealSky, RealSky
from cistrack.plugins.sensors.space_telescope import SpaceTelescope
from cistrack.scenario.loading import load_scenario
from cistrack.units import TU_S

from sensors.space_reference import cr3bp_state


@pytest.mark.parametrize("phase", [0.0, 0.3])
def test_observer_passes_the_catalog_state_phase_periods_before_the_epoch(phase):
    """phase p: the observer is at the catalog state at t = -p P, so again at t = (1 - p) P."""
    orbit = ORBITS["dro-2-1"]
    sensor = SpaceTelescope(orbit="dro-2-1", phase=phase)
    back = sensor.observer_states((1.0 - phase) * orbit.period)
    assert np.allclose(back, orbit.state, atol=1e-9)


def test_observer_follows_an_independent_propagation():
    sensor = SpaceTelescope(orbit="l2-lyapunov", phase=0.2)
    o = ORBITS["l2-lyapunov"]
    ref = cr3bp_state(np.array(o.state), -0.2 * o.period, 1.7)
    assert np.allclose(sensor.observer_states(1.7), ref, atol=1e-11)


def test_observer_from_a_state_and_an_earlier_epoch():
    """state_km given 6 h before the epoch: the observer is that state propagated by 6 h."""
    x0 = np.array(ORBITS["dro-2-1"].state)
    km = list(np.concatenate([x0[:3] * 384_400.0, x0[3:] * 384_400.0 / TU_S]))
    sensor = SpaceTelescope(orbit="", state_km=km, state_epoch="2025-12-31T18:00:00Z")
    assert np.allclose(sensor.observer_states(0.0), cr3bp_state(x0, -6 * 3600 / TU_S, 0.0), atol=1e-11)


def test_range_rate_is_the_time_derivative_of_range_along_the_truth():
    sensor = SpaceTelescope(orbit="dro-2-1", phase=0.4, measure_range=True, measure_range_rate=True)
    x0, t, h = np.array(ORBITS["nrho-9-2"].state), 0.8, 1e-5
    z = [sensor.measure(cr3bp_state(x0, 0.0, s)[None], s)[0] for s in (t - h, t, t + h)]
    assert z[1][3] == pytest.approx((z[2][2] - z[0][2]) / (2 * h), rel=1e-7)


def test_information_bound_jacobian_of_a_moving_observer_is_the_analytic_one():
    """d(RA, Dec)/d(position) of the geometric direction p = R(t) (r - o(t)): the bound's
    central differences against the closed form; velocity has no effect without light time."""
    sensor = SpaceTelescope(orbit="dro-2-1", phase=0.4, light_time=False, moon_phase_deg=30.0)
    x, t = cr3bp_state(np.array(ORBITS["nrho-9-2"].state), 0.0, 0.6), 0.6
    a = np.radians(30.0) + t
    rot = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
    px, py, pz = rot @ (x[:3] - sensor.observer_position(t))
    rho2, q2 = px * px + py * py + pz * pz, px * px + py * py
    d_ra = np.array([-py, px, 0.0]) / q2
    d_dec = np.array([-px * pz, -py * pz, q2]) / (rho2 * np.sqrt(q2))
    expected = np.zeros((2, 6))
    expected[:, :3] = np.stack([d_ra, d_dec]) @ rot
    h = measurement_jacobian(sensor, x, t, sensor.names)
    assert np.allclose(h, expected, rtol=1e-6, atol=1e-9 * np.abs(expected).max())


def test_passes_lie_inside_the_tasking_windows():
    sensor = SpaceTelescope(orbit="dro-2-1", phase=0.5, revisit_hours=24.0, window_hours=6.0,
                            first_window_hours=2.0, limiting_magnitude=0.0)
    x0 = np.array(ORBITS["nrho-9-2"].state)
    grid = np.linspace(0.0, 3 * 86400 / TU_S, 865)
    states = np.stack([cr3bp_state(x0, 0.0, s) for s in grid[::8]])
    passes = sensor.passes(grid[::8], states)
    assert passes
    for p in passes:
        start_h, end_h = p.start * TU_S / 3600 - 2.0 + 1e-9, p.end * TU_S / 3600 - 2.0 - 1e-9
        assert start_h >= 0 and np.floor(start_h / 24) == np.floor(end_h / 24) and end_h % 24 <= 6.0


def test_a_scenario_hands_its_dynamics_and_epoch_to_the_space_telescope():
    cr3bp = load_scenario("example-1-dro").build("sensor")
    assert isinstance(cr3bp._sky, IdealSky)
    eph = load_scenario("example-1-dro", overrides={"dynamics": {"name": "ephemeris"}}).build("sensor")
    assert isinstance(eph._sky, RealSky) and eph.dynamics.epoch == eph.epoch


@pytest.mark.parametrize("params, named", [
    (dict(orbit="halo-nowhere"), "orbit"),
    (dict(orbit="l2-transit", phase=0.5), "phase"),
    (dict(orbit="l2-lyapunov", state_km=[1e5, 0, 0, 0, 1.0, 0]), "orbit"),
    (dict(orbit="", state_km=[1e5, 0, 0, 0, 1.0, 0], state_epoch="2026-01-02T00:00:00Z"), "state_epoch"),
    (dict(state_km=[1e5, 0, 0]), "state_km"),
    (dict(revisit_hours=4.0, window_hours=8.0), "window_hours"),
    (dict(dynamics="cr3bp"), "dynamics"),
])
def test_bad_parameters_are_refused_naming_the_parameter(params, named):
    with pytest.raises(ParameterError, match=named):
        SpaceTelescope(**params)


def test_a_dynamics_model_with_another_epoch_is_refused():
    from cistrack.plugin.registry import default_registry
    eph = default_registry().create("dynamics", "ephemeris", epoch="2026-02-01T00:00:00Z")
    with pytest.raises(ParameterError, match="epoch"):
        SpaceTelescope(dynamics=eph, epoch="2026-01-01T00:00:00Z")


def test_an_observer_orbit_that_hits_the_moon_is_refused():
    km = [384_400.0 * (1 - 0.0121505), 0.0, 2000.0, 0.0, 0.0, 0.0]    # 2000 km above the Moon's centre, at rest
    sensor = SpaceTelescope(orbit="", state_km=km)
    with pytest.raises(ConfigError, match="hits Moon"):
        sensor.observer_position(1.0)


def test_a_target_flying_the_observers_own_orbit_is_refused_with_the_reason():
    from cistrack.errors import MeasurementError

    sensor = SpaceTelescope(orbit="nrho-9-2")
    x0 = np.array(ORBITS["nrho-9-2"].state)
    grid = np.linspace(0.0, 0.5, 20)
    states = np.stack([cr3bp_state(x0, 0.0, s) for s in grid])
    with pytest.raises(MeasurementError, match="comes within .* km of the observer .* cannot observe an object at its own"):
        sensor.passes(grid, states)
