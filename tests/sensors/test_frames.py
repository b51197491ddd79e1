"""Frame chain: az/el/range conversions, Earth rotation angle, synodic -> ECI geometry."""
from __future__ import annotations

from datetime import datetime, timedelta, timezone

import numpy as np

from cistrack.plugins.sensors.frames import (
    MU, EquatorialFrameModel, azelr_to_neu, earth_rotation_angle, geodetic_to_ecef, neu_to_azelr,
    wrap_azimuth,
)
from cistrack.units import TU_S


def test_az_el_range_round_trip_through_topocentric_vectors_to_1e_12():
    rng = np.random.default_rng(1)
    az = rng.uniform(0.0, 2 * np.pi, 1000)
    el = rng.uniform(-np.pi / 2 + 1e-6, np.pi / 2 - 1e-6, 1000)
    r = rng.uniform(0.2, 1.5, 1000)
    az2, el2, r2 = neu_to_azelr(azelr_to_neu(az, el, r))
    daz = (az2 - az + np.pi) % (2 * np.pi) - np.pi
    assert np.max(np.abs(daz * np.cos(el))) < 1e-12
    assert np.max(np.abs(el2 - el)) < 1e-12
    assert np.max(np.abs(r2 - r) / r) < 1e-12


def test_azimuth_is_in_zero_two_pi_and_never_two_pi():
    az, _, _ = neu_to_azelr(np.array([[1.0, -1e-300, 0.0], [1.0, -1e-17, 0.0], [-1.0, -1e-17, 0.0]]))
    assert np.all((az >= 0) & (az < 2 * np.pi))
    assert wrap_azimuth(-1e-17) < 2 * np.pi


def test_earth_rotation_angle_at_j2000_matches_iers_constant():
    j2000 = datetime(2000, 1, 1, 12, tzinfo=timezone.utc)
    assert np.isclose(earth_rotation_angle(j2000, 0.0), 2 * np.pi * 0.7790572732640, atol=1e-12)


def test_earth_rotation_angle_returns_after_one_sidereal_day():
    epoch = datetime(2026, 3, 1, 5, 17, 3, tzinfo=timezone.utc)
    sidereal_day_s = 86400.0 / 1.00273781191135448
    a0 = earth_rotation_angle(epoch, 0.0)
    a1 = earth_rotation_angle(epoch, sidereal_day_s / TU_S)
    assert abs((a1 - a0 + np.pi) % (2 * np.pi) - np.pi) < 1e-9


def test_earth_rotation_angle_does_not_depend_on_how_the_epoch_is_split():
    e0 = datetime(2026, 1, 1, tzinfo=timezone.utc)
    t = 3.7
    later = e0 + timedelta(seconds=t * TU_S)
    assert abs(earth_rotation_angle(e0, t) - earth_rotation_angle(later, 0.0)) < 1e-9


def test_moon_right_ascension_in_eci_is_phase_plus_time():
    fm = EquatorialFrameModel(datetime(2026, 1, 1, tzinfo=timezone.utc), moon_phase_deg=30.0)
    t = np.array([0.0, 0.5, 2.0])
    rot, earth = fm.synodic_to_eci(t)
    moon = np.einsum("kij,kj->ki", rot, np.array([1 - MU, 0, 0]) - earth)
    ra = np.arctan2(moon[:, 1], moon[:, 0])
    expected = (np.radians(30.0) + t + np.pi) % (2 * np.pi) - np.pi
    assert np.allclose(ra, expected, atol=1e-14)
    assert np.allclose(np.linalg.norm(moon, axis=1), 1.0)
    assert np.allclose(moon[:, 2], 0.0)


def test_geodetic_to_ecef_matches_wgs84_at_equator_and_pole():
    assert np.allclose(geodetic_to_ecef(0.0, 0.0, 0.0), [6378.137, 0.0, 0.0], atol=1e-9)
    assert np.allclose(geodetic_to_ecef(90.0, 0.0, 0.0), [0.0, 0.0, 6356.752314245], atol=1e-6)
