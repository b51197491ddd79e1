"""Two-body model against the closed-form universal-variable Kepler solution."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack import units
from cistrack.plugins.dynamics.twobody import TwoBody, gm_nondimensional, kepler_propagate

GM = gm_nondimensional(398600.4418)


def _orbits():
    """Circular LEO, eccentric MEO (3D), GEO transfer, hyperbolic flyby (LU, VU)."""
    def st(r_km, v_kms, incl=0.0):
        return np.r_[[r_km / units.LU_KM, 0.0, 0.0],
                     np.array([0.0, np.cos(incl), np.sin(incl)]) * v_kms / units.VU_KMS]
    return np.array([st(7000.0, np.sqrt(398600.4418 / 7000.0)),
                     st(20000.0, 5.2, 0.4),
                     st(6700.0, 10.15, 0.1),
                     st(8000.0, 11.5, 0.9)])


def test_gm_is_converted_with_the_project_units():
    assert GM == pytest.approx(398600.4418 * units.TU_S ** 2 / units.LU_KM ** 3, rel=1e-15)


def test_propagation_matches_closed_form_kepler_to_1e_10_relative():
    states = _orbits()
    times = np.array([0.002, 0.01, 0.03, 0.06])   # up to ~6 hours (3.5 LEO revolutions)
    prop = TwoBody().propagate(states, 0.0, times)
    for k, t in enumerate(times):
        exact = kepler_propagate(states, t, GM)
        rel_r = np.linalg.norm(prop.states[k, :, :3] - exact[:, :3], axis=1) / np.linalg.norm(exact[:, :3], axis=1)
        rel_v = np.linalg.norm(prop.states[k, :, 3:] - exact[:, 3:], axis=1) / np.linalg.norm(exact[:, 3:], axis=1)
        assert rel_r.max() <= 1e-10 and rel_v.max() <= 1e-10


def test_backward_propagation_matches_closed_form_kepler():
    states = _orbits()
    prop = TwoBody().propagate(states, 0.0, -0.03)
    exact = kepler_propagate(states, -0.03, GM)
    rel = np.linalg.norm(prop.final - exact, axis=1) / np.linalg.norm(exact, axis=1)
    assert rel.max() <= 1e-10


def test_kepler_returns_to_the_start_after_one_period():
    s = _orbits()[1]
    r, v = np.linalg.norm(s[:3]), np.linalg.norm(s[3:])
    a = 1.0 / (2.0 / r - v * v / GM)
    period = 2 * np.pi * np.sqrt(a ** 3 / GM)
    np.testing.assert_allclose(kepler_propagate(s, period, GM), s, rtol=0, atol=1e-13)


def test_kepler_conserves_energy_and_angular_momentum():
    states = _orbits()
    out = kepler_propagate(states, 0.37, GM)

    def energy(x):
        return 0.5 * np.sum(x[:, 3:] ** 2, 1) - GM / np.linalg.norm(x[:, :3], axis=1)

    np.testing.assert_allclose(energy(out), energy(states), rtol=1e-12)
    h0 = np.cross(states[:, :3], states[:, 3:])
    h1 = np.cross(out[:, :3], out[:, 3:])
    assert np.max(np.linalg.norm(h1 - h0, axis=1) / np.linalg.norm(h0, axis=1)) <= 1e-12


def test_kepler_forward_then_backward_is_the_identity():
    states = _orbits()[:3]
    back = kepler_propagate(kepler_propagate(states, 1.3, GM), -1.3, GM)
    rel = np.linalg.norm(back - states, axis=1) / np.linalg.norm(states, axis=1)
    assert rel.max() <= 1e-11


def test_trajectory_into_the_central_body_is_an_impact():
    s = np.array([[20000.0 / units.LU_KM, 0, 0, -3.0 / units.VU_KMS, 0.5 / units.VU_KMS, 0]])
    prop = TwoBody().propagate(s, 0.0, 0.1)
    assert not prop.alive[0] and np.all(np.isfinite(prop.states))
    assert np.linalg.norm(prop.final[0, :3]) * units.LU_KM == pytest.approx(6378.137, abs=1e-6)


def test_twobody_is_registered(registry):
    assert isinstance(registry.create("dynamics", "twobody"), TwoBody)
