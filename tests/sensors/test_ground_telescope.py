"""GroundTelescope: geometry of az/el, inverse line of sight, noise, residual, simulation."""
from __future__ import annotations

import pickle

import numpy as np
import pytest

from cistrack.errors import MeasurementError, ParameterError
from cistrack.plugins.sensors.frames import MU
from cistrack.plugins.sensors.ground_telescope import GroundTelescope
from cistrack.plugin.registry import load_registry
from cistrack.units import ARCSEC_RAD, LU_KM, TU_S

LAT, LON = 30.618963, -96.339214


def synodic_from_ecef_direction(sensor: GroundTelescope, direction_ecef, rho_lu: float, t: float):
    """Synodic state (1, 6) of a point at rho_lu from the observer along an ECEF direction.

    Built from the frame model's rotation and the WGS84 geometry only (not the NEU basis)."""
    rot, earth = sensor._frames.synodic_to_ecef(t)
    obs = sensor.observer_position(t) - earth
    d = np.asarray(direction_ecef, dtype=float)
    r = earth + obs + rot.T @ (rho_lu * d / np.linalg.norm(d))
    return np.concatenate([r, np.zeros(3)])[None, :]


def local_axes(lat_deg, lon_deg):
    la, lo = np.radians(lat_deg), np.radians(lon_deg)
    up = [np.cos(la) * np.cos(lo), np.cos(la) * np.sin(lo), np.sin(la)]
    north = [-np.sin(la) * np.cos(lo), -np.sin(la) * np.sin(lo), np.cos(la)]
    east = [-np.sin(lo), np.cos(lo), 0.0]
    return np.array(north), np.array(east), np.array(up)


def test_registered_as_sensor_ground_telescope():
    s = load_registry().create("sensor", "ground-telescope", measure_range=True)
    assert isinstance(s, GroundTelescope)
    assert s.names == ("azimuth", "elevation", "range")


def test_default_observer_is_college_station():
    s = GroundTelescope()
    assert (s.latitude_deg, s.longitude_deg, s.height_m) == (LAT, LON, 103.8)
    assert s.sigma_arcsec == 1.5 and s.elevation_mask_deg == 10.0


@pytest.mark.parametrize("t", [0.0, 0.37, 5.0])
def test_target_straight_above_observer_has_elevation_90_deg(telescope, t):
    _, _, up = local_axes(LAT, LON)
    x = synodic_from_ecef_direction(telescope, up, 1.0, t)
    assert np.isclose(telescope.measure(x, t)[0, 1], np.pi / 2, atol=1e-9)


@pytest.mark.parametrize("t", [0.0, 1.3])
def test_target_on_north_horizon_has_azimuth_0_elevation_0(telescope, t):
    north, _, _ = local_axes(LAT, LON)
    z = telescope.measure(synodic_from_ecef_direction(telescope, north, 1.0, t), t)[0]
    assert min(z[0], 2 * np.pi - z[0]) < 1e-10
    assert abs(z[1]) < 1e-10


@pytest.mark.parametrize("t", [0.0, 2.1])
def test_target_due_east_has_azimuth_90_deg(telescope, t):
    _, east, _ = local_axes(LAT, LON)
    z = telescope.measure(synodic_from_ecef_direction(telescope, east, 1.0, t), t)[0]
    assert np.isclose(z[0], np.pi / 2, atol=1e-10)
    assert abs(z[1]) < 1e-10


def test_measure_range_is_distance_from_observer():
    s = GroundTelescope(measure_range=True)
    rng = np.random.default_rng(0)
    x = np.column_stack([rng.uniform(-1.2, 1.2, (50, 3)), np.zeros((50, 3))])
    t = 0.8
    d = np.linalg.norm(x[:, :3] - s.observer_position(t), axis=1)
    assert np.allclose(s.measure(x, t)[:, 2], d, rtol=1e-13)


def test_line_of_sight_and_range_recover_the_synodic_position():
    s = GroundTelescope(measure_range=True)
    rng = np.random.default_rng(2)
    x = np.column_stack([rng.uniform(-1.2, 1.2, (200, 3)), rng.normal(size=(200, 3))])
    t = rng.uniform(0, 10, 200)
    z = s.measure(x, t)
    assert np.allclose(s.positions_from_measurements(z, t), x[:, :3], atol=1e-12)
    los = s.line_of_sight(z[:, :2], t)
    assert np.allclose(np.linalg.norm(los, axis=1), 1.0)
    assert np.allclose(s.observer_position(t) + z[:, 2:3] * los, x[:, :3], atol=1e-12)


def test_measure_with_per_row_times_equals_row_by_row_scalar_calls(telescope, nrho_arc):
    times, states = nrho_arc
    idx = np.arange(0, len(times), 37)
    batch = telescope.measure(states[idx], times[idx])
    single = np.vstack([telescope.measure(states[i:i + 1], float(times[i])) for i in idx])
    assert np.array_equal(batch, single) or np.allclose(batch, single, atol=1e-15)


def test_innovation_across_the_azimuth_seam_is_small(telescope):
    eps = 3e-6
    z = np.array([[eps, 0.5]])
    zhat = np.array([[2 * np.pi - eps, 0.5]])
    r = telescope.residual(z, zhat)
    assert np.allclose(r, [[2 * eps, 0.0]], atol=1e-15)
    assert np.allclose(telescope.residual(zhat, z), [[-2 * eps, 0.0]], atol=1e-15)


def test_measured_azimuths_of_targets_either_side_of_north_differ_by_a_small_residual(telescope):
    north, east, _ = local_axes(LAT, LON)
    a = synodic_from_ecef_direction(telescope, north + 1e-5 * east, 1.0, 0.0)
    b = synodic_from_ecef_direction(telescope, north - 1e-5 * east, 1.0, 0.0)
    za, zb = telescope.measure(a, 0.0), telescope.measure(b, 0.0)
    assert abs(za[0, 0] - zb[0, 0]) > 6.0                       # raw values straddle the seam
    assert np.allclose(telescope.residual(za, zb)[0, 0], 2e-5, rtol=1e-4)


def test_angle_sigmas_are_1p5_arcsec_and_range_sigma_is_alpha_times_range():
    s = GroundTelescope(measure_range=True, range_alpha=0.07)
    x = np.array([[1 - MU, 0.0, 0.0, 0.0, 0.0, 0.0]])
    sig = s.sigmas(x, 0.0)
    assert np.allclose(sig[0, :2], 1.5 * ARCSEC_RAD)
    assert np.isclose(sig[0, 2], 0.07 * s.measure(x, 0.0)[0, 2])
    assert s.noise_covariance(x, 0.0).shape == (1, 3, 3)


def test_simulated_noise_has_the_stated_sigma_and_azimuth_in_range(telescope, nrho_arc):
    times, states = nrho_arc
    rng = np.random.default_rng(7)
    idx = np.repeat(np.arange(0, len(times), 10), 40)
    # measurement times must increase: use distinct tiny offsets on a fixed (slowly moving) target
    t = times[idx] + np.tile(np.arange(40) * 1e-9, len(idx) // 40)
    ms = telescope.simulate(states[idx], t, rng)
    assert ms.names == ("azimuth", "elevation")
    assert np.all((ms.values[:, 0] >= 0) & (ms.values[:, 0] < 2 * np.pi))
    r = telescope.residual(ms.values, telescope.measure(states[idx], t))
    assert np.allclose(np.std(r, axis=0) / ARCSEC_RAD, 1.5, rtol=0.05)
    assert np.allclose(np.mean(r, axis=0) / ARCSEC_RAD, 0.0, atol=0.1)


def test_simulation_is_reproducible_from_the_generator(telescope, nrho_arc):
    times, states = nrho_arc
    a = telescope.simulate(states[:20], times[:20], np.random.default_rng(3))
    b = telescope.simulate(states[:20], times[:20], np.random.default_rng(3))
    assert np.array_equal(a.values, b.values)


def test_visible_follows_the_elevation_mask(nrho_arc):
    times, states = nrho_arc
    s = GroundTelescope(elevation_mask_deg=25.0)
    el = s.measure(states, times)[:, 1]
    assert np.array_equal(s.visible(states, times), el >= np.radians(25.0))


def _lower_culmination_phase(s: GroundTelescope) -> float:
    """Moon phase (deg) that puts a target at the Moon's position at lower culmination at t = 0."""
    from cistrack.plugins.sensors.frames import earth_rotation_angle
    era = np.degrees(earth_rotation_angle(s._epoch, 0.0))
    return float((era + s.longitude_deg - 180.0) % 360.0)


def test_distant_target_gives_one_pass_of_10_to_20_hours_per_sidereal_day():
    probe = GroundTelescope()
    s = GroundTelescope(moon_phase_deg=_lower_culmination_phase(probe))
    sidereal_day = 86164.0905 / TU_S
    times = np.linspace(0.0, sidereal_day, 24 * 12 + 1)
    states = np.tile([1 - MU, 0.0, 0.0, 0.0, 0.0, 0.0], (times.size, 1))
    passes = s.passes(times, states)
    assert len(passes) == 1
    hours = passes[0].duration * TU_S / 3600.0
    assert 10.0 <= hours <= 20.0
    # closed form for a geocentric target on the equator, corrected for the hour-angle rate
    rate = 2 * np.pi * 1.00273781191135448 / 86400.0 - 1.0 / TU_S        # rad/s
    h = np.arccos(np.sin(np.radians(10.0)) / np.cos(np.radians(LAT)))
    assert abs(hours - 2 * h / rate / 3600.0) < 0.3                      # parallax ~1 deg


def test_pass_edges_are_refined_onto_the_mask():
    s = GroundTelescope(moon_phase_deg=_lower_culmination_phase(GroundTelescope()))
    times = np.linspace(0.0, 0.3, 40)                                     # ~40 minutes apart
    states = np.tile([1 - MU, 0.0, 0.0, 0.0, 0.0, 0.0], (times.size, 1))
    (p,) = s.passes(times, states)
    el = s.measure(states[:2], np.array([p.start, p.end]))[:, 1]
    assert np.allclose(el, np.radians(10.0), atol=1e-9)


def test_nrho_passes_last_10_to_20_hours(telescope, nrho_arc):
    times, states = nrho_arc
    passes = telescope.passes(times, states)
    full = [p for p in passes if p.start > times[0] and p.end < times[-1]]
    assert len(full) >= 3
    for p in full:
        assert 8.0 < p.duration * TU_S / 3600.0 < 20.0


def test_component_pickles():
    s = GroundTelescope(measure_range=True, epoch="2027-05-05T10:00:00Z", moon_phase_deg=12.0)
    s2 = pickle.loads(pickle.dumps(s))
    x = np.array([[1.0, 0.1, -0.1, 0.0, 0.0, 0.0]])
    assert np.array_equal(s.measure(x, 1.0), s2.measure(x, 1.0))
    assert s2.get_params() == s.get_params()


@pytest.mark.parametrize("params", [
    {"sigma_arcsec": 0.0}, {"latitude_deg": 95.0}, {"epoch": "yesterday"},
    {"frame_model": "ephemeris"}, {"measure_range": "yes"}, {"range_alpha": -0.1},
    {"elevation_mask_deg": 90.0},
])
def test_invalid_parameters_raise_parameter_error(params):
    with pytest.raises(ParameterError):
        GroundTelescope(**params)


def test_nan_states_raise_measurement_error(telescope):
    with pytest.raises(MeasurementError):
        telescope.measure(np.full((2, 6), np.nan), 0.0)


def test_wrong_number_of_times_raises_measurement_error(telescope):
    with pytest.raises(MeasurementError):
        telescope.measure(np.ones((3, 6)), np.zeros(2))


def test_observer_is_one_earth_radius_from_the_earth_centre(telescope):
    t = np.linspace(0, 3, 7)
    d = np.linalg.norm(telescope.observer_position(t) - np.array([-MU, 0, 0]), axis=1) * LU_KM
    assert np.all((d > 6372.0) & (d < 6374.0))                # WGS84 radius at 30.6 deg + 104 m


def test_equatorial_target_at_upper_culmination_is_due_south_at_90_minus_latitude():
    probe = GroundTelescope()
    s = GroundTelescope(moon_phase_deg=(_lower_culmination_phase(probe) + 180.0) % 360.0)
    z = s.measure(np.array([[1 - MU, 0.0, 0.0, 0.0, 0.0, 0.0]]), 0.0)[0]
    assert np.isclose(np.degrees(z[0]), 180.0, atol=1e-6)
    parallax = np.degrees(np.arcsin(6373.0 / 384400.0 * np.cos(np.radians(90 - LAT))))
    assert np.isclose(np.degrees(z[1]), 90.0 - LAT - parallax, atol=0.05)


def test_a_distant_target_rises_in_the_east_and_sets_in_the_west():
    s = GroundTelescope(moon_phase_deg=_lower_culmination_phase(GroundTelescope()))
    times = np.linspace(0.0, 86164.0905 / TU_S, 24 * 12 + 1)
    states = np.tile([1 - MU, 0.0, 0.0, 0.0, 0.0, 0.0], (times.size, 1))
    (p,) = s.passes(times, states)
    az = np.degrees(s.measure(states[:2], np.array([p.start, p.end]))[:, 0])
    assert 0.0 < az[0] < 180.0 and 180.0 < az[1] < 360.0


def test_radec_is_the_direction_of_the_azel_line_of_sight_in_eci_axes():
    """RA/Dec of angles = "radec" point where the az/el telescope at the same site looks,
    expressed in the frame model's ECI axes (right ascension of the synodic x axis = moon_phase + t)."""
    from cistrack.testing.fixtures import lunar_distance_states
    x, t, phase = lunar_distance_states(4), 0.37, 25.0
    azel = GroundTelescope(moon_phase_deg=phase)
    radec = GroundTelescope(moon_phase_deg=phase, angles="radec")
    los = azel.line_of_sight(azel.measure(x, t), t)
    a = np.radians(phase) + t
    eci = los @ np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]]).T
    ra = np.mod(np.arctan2(eci[:, 1], eci[:, 0]), 2 * np.pi)
    dec = np.arcsin(eci[:, 2])
    z = radec.measure(x, t)
    assert np.allclose(z[:, 0], ra, atol=1e-12) and np.allclose(z[:, 1], dec, atol=1e-12)


def test_repeated_times_give_the_same_measurements_as_a_fresh_sensor():
    """The sensor keeps the last time's frame; measuring at t1, t2, t1 must not reuse t2's."""
    x = np.array([[1.0221, 0.0, -0.1821, 0.0, -0.1033, 0.0], [0.9, 0.1, 0.05, 0.0, 0.1, 0.0]])
    used = GroundTelescope(latitude_deg=LAT, longitude_deg=LON)
    first = used.measure(x, 0.3)
    used.measure(x, 0.7)
    again = used.measure(x, 0.3)
    fresh = GroundTelescope(latitude_deg=LAT, longitude_deg=LON).measure(x, 0.3)
    assert np.array_equal(first, fresh) and np.array_equal(again, fresh)


def test_a_pickled_sensor_measures_as_the_original():
    s = GroundTelescope(latitude_deg=LAT, longitude_deg=LON)
    x = np.array([[1.0221, 0.0, -0.1821, 0.0, -0.1033, 0.0]])
    s.measure(x, 0.3)
    assert np.array_equal(pickle.loads(pickle.dumps(s)).measure(x, 0.5), s.measure(x, 0.5))


def test_the_sites_height_range_is_the_sensors():
    """One range for a site's height wherever it is given ([-12000, 100000] m; bundled MPC sites reach -9254)."""
    assert GroundTelescope(height_m=-11_000.0).height_m == -11_000.0
    with pytest.raises(ParameterError, match="height_m"):
        GroundTelescope(height_m=-12_001.0)
