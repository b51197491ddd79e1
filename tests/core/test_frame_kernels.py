"""The compiled synodic <-> GCRS conversions do the numpy formulas' operations in a fixed order:
the same numbers bit for bit as those formulas written out with that order, at one time for
every state and at a time per state, and the ephemeris model's LU/VU entry points equal the km
conversions scaled as before."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack import units
from cistrack.astro.earth_moon import EarthMoonFrame

JD0 = (2_461_041.5, 0.0)  # 2026-01-01 00:00 TDB


@pytest.fixture(scope="module")
def frame():
    return EarthMoonFrame(JD0)


def _rotate(rot, v):
    """rot (M, 3, 3) applied to v (N, 3), each row's sum in the order (0 + 2) + 1."""
    p = rot * v[:, None, :]
    return (p[:, :, 0] + p[:, :, 2]) + p[:, :, 1]


def _rotate_back(rot, v):
    """rot transposed applied to v, each row's sum in the order (0 + 1) + 2."""
    p = np.transpose(rot, (0, 2, 1)) * v[:, None, :]
    return (p[:, :, 0] + p[:, :, 1]) + p[:, :, 2]


def _times(rng, n, per_state):
    return rng.uniform(0.0, 8.0, n) if per_state else 1.3


@pytest.mark.parametrize("per_state", [False, True], ids=["one-time", "time-per-state"])
def test_synodic_to_gcrs_is_the_written_out_formula_bit_for_bit(frame, rng, per_state):
    s = rng.normal(size=(300, 6))
    t = _times(rng, 300, per_state)
    ax = frame.axes(np.atleast_1d(t))
    rho = _rotate(ax.rotation, s[:, :3] * units.LU_KM)
    rhod = _rotate(ax.rotation, s[:, 3:] * units.VU_KMS)
    want = np.hstack([ax.origin + rho, ax.origin_velocity + rhod + np.cross(ax.omega, rho)])
    assert np.array_equal(frame.synodic_to_gcrs(s, t), want)


@pytest.mark.parametrize("per_state", [False, True], ids=["one-time", "time-per-state"])
def test_gcrs_to_synodic_is_the_written_out_formula_bit_for_bit(frame, rng, per_state):
    s = rng.normal(size=(300, 6)) * np.r_[[4e5] * 3, [1.0] * 3]
    t = _times(rng, 300, per_state)
    ax = frame.axes(np.atleast_1d(t))
    rel = s[:, :3] - ax.origin
    relv = s[:, 3:] - ax.origin_velocity - np.cross(ax.omega, rel)
    want = np.hstack([_rotate_back(ax.rotation, rel) / units.LU_KM, _rotate_back(ax.rotation, relv) / units.VU_KMS])
    assert np.array_equal(frame.gcrs_to_synodic(s, t), want)


def test_the_ephemeris_models_kernel_states_are_the_km_conversions_scaled(rng):
    from cistrack.plugins.dynamics.ephemeris import EphemerisDynamics

    model = EphemerisDynamics(epoch="2026-01-01T00:00:00Z")
    s = rng.normal(size=(200, 6)) * 0.4
    inertial = model.to_inertial(s, 0.9)
    assert np.array_equal(inertial, units.state_from_km(model.frame.synodic_to_gcrs(s, 0.9)))
    assert np.array_equal(model.from_inertial(inertial, 0.9),
                          model.frame.gcrs_to_synodic(units.state_to_km(inertial), 0.9))


def test_a_single_state_gives_a_single_state(frame):
    s = np.array([1.0, 0.1, -0.2, 0.01, 0.3, 0.0])
    out = frame.synodic_to_gcrs(s, 0.5)
    assert out.shape == (6,) and np.array_equal(frame.synodic_to_gcrs(s[None], 0.5)[0], out)


def test_an_unknown_unit_is_refused_with_the_allowed_ones(frame):
    with pytest.raises(ValueError, match="unit must be 'km' or 'lu'.*'au'"):
        frame.synodic_to_gcrs(np.zeros(6), 0.0, unit="au")
