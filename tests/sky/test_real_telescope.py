"""Sensor 'real-telescope': real Earth-Moon frame + ERFA observer + cistrack.astro.sky measurements."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from cistrack.errors import MeasurementError, ParameterError
from cistrack.astro.earth_moon import EarthMoonFrame
from cistrack.astro.observer import ObserverGeometry, neu_basis
from cistrack.astro.sites import Site
from cistrack.plugins.iod.kinematic_presets import NoisyRangeIOD, UniformRangeIOD
from cistrack.plugins.sensors.real_telescope import RealTelescope
from cistrack.plugins.sensors.schedules import PaperExample1Schedule
from cistrack.astro.sky import apparent_azel, astrometric_radec
from cistrack.testing import parametrize_with_checks
from cistrack.testing.fixtures import lunar_distance_states
from cistrack.units import TU_S, hours_to_tu

from reference_cr3bp import cr3bp_rhs  # noqa: E402  (tests/ is on sys.path)

EPOCH = "2026-01-01T00:00:00Z"


@parametrize_with_checks([RealTelescope, RealTelescope(measurement="radec"),
                          RealTelescope(measure_range=True, refraction=True)])
def test_conformance(component, check):
    check(component)


def test_registered_as_sensor_real_telescope(registry):
    assert isinstance(registry.create("sensor", "real-telescope"), RealTelescope)


@pytest.mark.parametrize("measurement", ["azel", "radec"])
def test_measure_is_the_frame_transform_followed_by_the_sky_model(measurement):
    sensor = RealTelescope(measurement=measurement, epoch=EPOCH, refraction=measurement == "azel")
    x = lunar_distance_states(5)
    t = 0.05 * np.arange(5)
    g = EarthMoonFrame.from_utc(EPOCH).synodic_to_gcrs(x, t)
    site = Site(sensor.latitude_deg, sensor.longitude_deg, sensor.height_m)
    obs = ObserverGeometry(site, EPOCH).state(t * TU_S)
    if measurement == "azel":
        a, b, _ = apparent_azel(g[:, :3], g[:, 3:], obs, neu_basis(site), sensor.corrections,
                                site.height_m)
    else:
        a, b, _ = astrometric_radec(g[:, :3], g[:, 3:], obs)
    np.testing.assert_allclose(sensor.measure(x, t), np.stack([a, b], axis=1), rtol=0, atol=1e-12)


def test_names_follow_the_measurement_kind():
    assert RealTelescope(measurement="radec", measure_range=True).names == (
        "right_ascension", "declination", "range")
    assert RealTelescope().names == ("azimuth", "elevation")


def test_radec_refuses_aberration_and_refraction_by_name():
    with pytest.raises(ParameterError, match="annual_aberration"):
        RealTelescope(measurement="radec", annual_aberration=True)
    with pytest.raises(ParameterError, match="refraction"):
        RealTelescope(measurement="radec", refraction=True)


def test_an_unknown_measurement_kind_is_refused_with_the_choices():
    with pytest.raises(ParameterError, match="radec"):
        RealTelescope(measurement="altaz")


def test_simulated_sets_name_every_correction_applied():
    sensor = RealTelescope(refraction=True, polar_motion=False)
    x = lunar_distance_states(3)
    ms = sensor.simulate(x, np.array([0.0, 0.01, 0.02]), np.random.default_rng(3))
    assert ms.meta["corrections"] == ["ut1", "light_time", "annual_aberration",
                                      "diurnal_aberration", "refraction"]
    assert ms.meta["measurement"] == "azel"


def test_line_of_sight_undoes_refraction_and_aberration_up_to_the_target_motion():
    # a target at rest in the GCRS: only the light time of a resting target remains, zero miss
    sensor = RealTelescope(epoch=EPOCH, refraction=True)
    frame = EarthMoonFrame.from_utc(EPOCH)
    obs = sensor._observer.state(0.0)
    r = obs.position_km[0] + np.array([2.0e5, -1.0e5, 1.5e5])
    x = frame.gcrs_to_synodic(np.concatenate([r, np.zeros(3)])[None, :], 0.0)
    z = sensor.measure(x, 0.0)
    los = sensor.line_of_sight(z, 0.0)
    o = sensor.observer_position(0.0)
    rho = np.linalg.norm(x[0, :3] - o)
    assert np.linalg.norm(o + rho * los[0] - x[0, :3]) * 384400.0 < 0.01    # km


def test_malformed_times_are_refused():
    with pytest.raises(MeasurementError, match="NaN"):
        RealTelescope().measure(lunar_distance_states(2), np.array([0.0, np.nan]))


def _nrho_scenario(sensor):
    x0 = [1.0221, 0.0, -0.1821, 0.0, -0.1033, 0.0]
    t_end = 3 * 86400.0 / 375149.0
    sol = solve_ivp(cr3bp_rhs, (0.0, t_end), x0, rtol=1e-12, atol=1e-13, method="DOP853",
                    dense_output=True)
    grid = np.arange(0.0, t_end, hours_to_tu(1.0 / 6.0))
    passes = [p for p in sensor.passes(grid, sol.sol(grid).T) if p.start > 0.0]
    times = PaperExample1Schedule().plan(passes, t_end, np.random.default_rng(2025))
    return sol.sol, times


@pytest.mark.parametrize("iod_cls", [NoisyRangeIOD, UniformRangeIOD])
def test_kinematic_iod_works_from_astrometric_radec(iod_cls):
    # The CR3BP NRHO read as a state of the real frame (the truth only has to be smooth).
    sensor = RealTelescope(measurement="radec", measure_range=True, epoch=EPOCH)
    truth, times = _nrho_scenario(sensor)
    inside = 0
    for seed in range(10):
        rng = np.random.default_rng(seed)
        ms = sensor.simulate(truth(times).T, times, rng)
        cloud = iod_cls(n_particles=1000).estimate(ms, sensor, rng)
        d = truth(cloud.epoch) - cloud.mean
        inside += float(d @ np.linalg.solve(cloud.covariance, d)) <= 16.81     # chi2(6) 99 %
    assert inside >= 9


def test_a_run_with_the_real_sky_names_its_corrections_in_the_manifest(tmp_path):
    from cistrack.results.store import read_manifest
    from cistrack.runs.pipeline import run_scenario
    from cistrack.scenario.loading import load_scenario

    s = load_scenario("quick").with_overrides({
        "duration_days": 1.4, "filter": {"name": "ukf"}, "iod": {"n_particles": 300},
        "sensor": {"name": "real-telescope", "measurement": "radec", "measure_range": True}})
    run_scenario(s, seed=3, output_dir=tmp_path / "r")
    model = read_manifest(tmp_path / "r")["measurement_model"]
    assert model["sensor"] == "real-telescope" and model["measurement"] == "radec"
    assert model["corrections"] == ["ut1", "polar_motion", "light_time"]


def test_ground_telescope_points_a_real_frame_request_to_real_telescope():
    from cistrack.plugins.sensors.ground_telescope import GroundTelescope

    with pytest.raises(ParameterError, match="real-telescope"):
        GroundTelescope(frame_model="real")


def test_the_real_sky_sensor_works_with_the_network_unreachable():
    # Fresh interpreter, every socket connection refused: IERS tables, leap seconds, DE421 and
    # ERFA all come from installed packages.
    import subprocess
    import sys
    import textwrap

    code = textwrap.dedent("""
        import socket
        def refuse(*a, **k):
            raise RuntimeError("network access attempted")
        socket.socket.connect = refuse
        socket.create_connection = refuse
        import numpy as np
        from cistrack.plugins.sensors.real_telescope import RealTelescope
        from cistrack.testing.fixtures import lunar_distance_states
        for epoch in ("2001-02-03T04:05:06Z", "2049-12-01T00:00:00Z"):
            for kind in ("azel", "radec"):
                z = RealTelescope(measurement=kind, epoch=epoch).measure(lunar_distance_states(3), 0.1)
                assert np.all(np.isfinite(z))
        print("offline-ok")
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert "offline-ok" in out.stdout


def test_a_bundled_observatory_far_below_the_ellipsoid_is_a_valid_site_for_the_sensor():
    """The site checks and the sensor share one height range: observatory 506's rounded parallax
    constants put it 9,254 m below the ellipsoid, and predict --site 506 had failed on the sensor's
    narrower [-1000, 100000]."""
    from cistrack.astro.sites import observatory

    site = observatory("506")
    sensor = RealTelescope(latitude_deg=site.latitude_deg, longitude_deg=site.longitude_deg, height_m=site.height_m)
    assert sensor.height_m == site.height_m < -9000.0

