"""Exclusion cones and the detection model, at their boundaries (plugins/sensors/visibility_rules.py)
and as the space telescope applies them."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.astro.primaries import MOON_RADIUS_KM, MU_EARTH_MOON
from cistrack.plugins.sensors.space_telescope import SpaceTelescope
from cistrack.plugins.sensors.visibility_rules import (ExclusionRules, Photometry, apparent_magnitude,
                                                       lambert_phase_function, limb_margins)
from cistrack.units import LU_KM

AU = 149_597_870.7


def _rotated(u: np.ndarray, angle: float) -> np.ndarray:
    """u (3,) unit turned by ``angle`` rad towards a perpendicular direction."""
    w = np.cross(u, [0.0, 0.0, 1.0])
    w /= np.linalg.norm(w)
    return np.cos(angle) * u + np.sin(angle) * w


def test_limb_margin_is_the_angle_to_the_centre_minus_the_apparent_radius():
    body = np.array([[1000.0, 0.0, 0.0]])
    los = _rotated(np.array([1.0, 0.0, 0.0]), 0.3)[None]
    assert limb_margins(los, body, 100.0)[0] == pytest.approx(0.3 - np.arcsin(0.1), abs=1e-15)


@pytest.mark.parametrize("offset, allowed", [(1e-9, True), (-1e-9, False)])
def test_exclusion_boundary_is_the_limb_plus_the_angle(offset, allowed):
    rules = ExclusionRules(moon_deg=5.0)
    body = np.array([[1000.0, 0.0, 0.0]])
    los = _rotated(np.array([1.0, 0.0, 0.0]), np.arcsin(0.1) + np.radians(5.0) + offset)[None]
    assert rules.allowed(los, {"moon": body}, {"moon": 100.0})[0] == allowed


def test_negative_exclusion_angle_turns_the_cone_off():
    los = np.array([[1.0, 0.0, 0.0]])       # straight at the body's centre
    assert ExclusionRules().allowed(los, {"moon": los * 1000.0}, {"moon": 100.0})[0]


def test_magnitude_at_zero_phase_is_the_closed_form():
    """m = m_sun - 2.5 log10((2/3) p (D/2)^2 / rho^2) at phase 0 and 1 AU from the Sun."""
    rho_km = LU_KM
    obs_to_target = np.array([[rho_km, 0.0, 0.0]])
    sun_to_target = np.array([[AU, 0.0, 0.0]])          # Sun behind the observer: phase 0
    expected = -26.74 - 2.5 * np.log10((2 / 3) * 0.2 * 1.0 ** 2 / (rho_km * 1e3) ** 2)
    assert apparent_magnitude(obs_to_target, sun_to_target, 2.0, 0.2)[0] == pytest.approx(expected, abs=1e-12)
    assert expected == pytest.approx(18.37, abs=0.01)


def test_phase_function_is_one_at_zero_half_over_pi_at_quadrature_and_zero_at_full_phase():
    assert lambert_phase_function(np.array([0.0, np.pi / 2, np.pi])) == pytest.approx([1.0, 1.0 / np.pi, 0.0], abs=1e-15)


@pytest.mark.parametrize("delta, detected", [(1e-9, True), (-1e-9, False)])
def test_detection_boundary_is_the_limiting_magnitude(delta, detected):
    o, s = np.array([[LU_KM, 0.0, 0.0]]), np.array([[AU, AU * 0.1, 0.0]])
    m = apparent_magnitude(o, s, 2.0, 0.2)[0]
    assert Photometry(2.0, 0.2, limiting_magnitude=m + delta).detected(o, s)[0] == detected


def test_a_target_at_full_phase_is_never_detected():
    o, s = np.array([[1000.0, 0.0, 0.0]]), np.array([[-AU, 0.0, 0.0]])
    assert not Photometry(2.0, 0.2, limiting_magnitude=40.0).detected(o, s)[0]


@pytest.mark.parametrize("delta, detected", [(1e-6, True), (-1e-6, False)])
def test_detection_boundary_is_the_maximum_range(delta, detected):
    o, s = np.array([[50_000.0, 0.0, 0.0]]), np.array([[AU, 0.0, 0.0]])
    assert Photometry(max_range_km=50_000.0 + delta).detected(o, s)[0] == detected


@pytest.mark.parametrize("offset, visible", [(1e-7, True), (-1e-7, False)])
def test_space_telescope_moon_exclusion_boundary(offset, visible):
    """A target placed just outside / inside the Moon's cone as seen from a DRO observer."""
    sensor = SpaceTelescope(orbit="dro-2-1", phase=0.1, sun_exclusion_deg=-1, earth_exclusion_deg=-1,
                            moon_exclusion_deg=5.0, limiting_magnitude=0.0)
    t = 0.2
    obs = sensor.observer_position(t)
    to_moon = np.array([1.0 - MU_EARTH_MOON, 0.0, 0.0]) - obs
    d = np.linalg.norm(to_moon)
    half = np.arcsin(MOON_RADIUS_KM / LU_KM / d)
    u = _rotated(to_moon / d, half + np.radians(5.0) + offset)
    target = np.concatenate([obs + 0.5 * u, np.zeros(3)])[None]
    assert sensor.visible(target, t)[0] == visible


def test_space_telescope_limiting_magnitude_decides_visibility():
    """The same geometry seen with a faint and a bright limiting magnitude."""
    kw = dict(orbit="dro-2-1", phase=0.1, sun_exclusion_deg=-1, earth_exclusion_deg=-1, moon_exclusion_deg=-1)
    x = np.array([[1.02, 0.0, -0.18, 0.0, -0.1, 0.0]])
    assert SpaceTelescope(limiting_magnitude=30.0, **kw).visible(x, 0.2)[0]
    assert not SpaceTelescope(limiting_magnitude=5.0, **kw).visible(x, 0.2)[0]
