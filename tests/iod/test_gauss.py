"""Gauss's angles-only method: textbook example, a synthetic Kepler orbit, frames, and the
cislunar failure it is the baseline for."""
from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp
from scipy.stats import chi2

from cistrack.plugins.iod.gauss import (MU_EARTH_MOON, GaussIOD, eci_to_synodic,
                                        gauss_angles_only, synodic_to_eci)

DEG = np.pi / 180.0


def _curtis_example_5_11():
    """Curtis, Orbital Mechanics for Engineering Students, Example 5.11: station at 40 deg N,
    1 km altitude (Re = 6378 km, f = 0.003353), LST, topocentric RA/Dec at t = 0, 118.10,
    237.58 s; mu = 398600 km^3/s^2."""
    re, f, h, phi = 6378.0, 0.003353, 1.0, 40.0 * DEG
    lst = np.array([44.506, 45.000, 45.499]) * DEG
    ra = np.array([43.537, 54.420, 64.318]) * DEG
    dec = np.array([-8.7833, -12.074, -15.105]) * DEG
    t = np.array([0.0, 118.10, 237.58])
    den = np.sqrt(1.0 - (2.0 * f - f * f) * np.sin(phi) ** 2)
    R = np.stack([(re / den + h) * np.cos(phi) * np.cos(lst),
                  (re / den + h) * np.cos(phi) * np.sin(lst),
                  np.full(3, (re * (1.0 - f) ** 2 / den + h) * np.sin(phi))], axis=1)
    L = np.stack([np.cos(dec) * np.cos(ra), np.cos(dec) * np.sin(ra), np.sin(dec)], axis=1)
    return R, L, t


def test_curtis_example_5_11_station_positions():
    R, _, _ = _curtis_example_5_11()
    np.testing.assert_allclose(R, [[3489.8, 3430.2, 4078.5], [3460.1, 3460.1, 4078.5],
                                   [3429.9, 3490.1, 4078.5]], atol=0.1)


def test_curtis_example_5_11_state_at_the_middle_observation():
    R, L, t = _curtis_example_5_11()
    sol = gauss_angles_only(R, L, t, 398600.0)
    assert sol.valid[0]
    # Book: r2 = 5659.1 I + 6533.8 J + 3270.1 K km, worked with 4-5 significant intermediates;
    # full precision moves it by < 1.5 km.
    np.testing.assert_allclose(sol.r[0, 1], [5659.1, 6533.8, 3270.1], atol=1.5)
    # Full-precision result of the same algorithm (matches an independent open-source
    # implementation of Curtis's Algorithm 5.5 to 1e-4 km/s).
    np.testing.assert_allclose(sol.v2[0], [-3.8791, 5.1196, -2.2409], atol=2e-4)


def _kepler(mu, x0, t):
    sol = solve_ivp(lambda _t, s: np.r_[s[3:], -mu * s[:3] / np.linalg.norm(s[:3]) ** 3],
                    (0.0, t[-1]), x0, t_eval=t, rtol=1e-12, atol=1e-9, method="DOP853")
    return sol.y.T


def test_recovers_a_two_body_orbit_from_its_own_lines_of_sight():
    mu = 398600.0
    x0 = np.array([7000.0, 1000.0, 2000.0, -1.0, 7.0, 2.5])       # ~LEO, e ~ 0.1
    t = np.array([0.0, 60.0, 120.0])
    truth = _kepler(mu, x0, t)
    w = 7.292115e-5
    R = 6378.0 * np.stack([np.cos(w * t) * 0.7, np.sin(w * t) * 0.7, np.full(3, 0.714)], axis=1)
    los = truth[:, :3] - R
    los /= np.linalg.norm(los, axis=1, keepdims=True)
    sol = gauss_angles_only(R, los, t, mu)
    # truncated f and g series: O((mu/r^3) tau^2) ~ 1e-3 relative error over 1 minute
    assert np.linalg.norm(sol.r[0, 1] - truth[1, :3]) < 1e-3 * np.linalg.norm(truth[1, :3])
    assert np.linalg.norm(sol.v2[0] - truth[1, 3:]) < 5e-3 * np.linalg.norm(truth[1, 3:])


def test_vectorised_samples_match_one_at_a_time():
    R, L, t = _curtis_example_5_11()
    rng = np.random.default_rng(0)
    Ls = L[None] + 1e-5 * rng.standard_normal((5, 3, 3))
    Ls /= np.linalg.norm(Ls, axis=2, keepdims=True)
    many = gauss_angles_only(R, Ls, t, 398600.0)
    for i in range(5):
        one = gauss_angles_only(R, Ls[i], t, 398600.0)
        np.testing.assert_allclose(many.v2[i], one.v2[0], rtol=1e-10)


def test_synodic_eci_round_trip():
    s = np.random.default_rng(1).normal(size=(10, 6))
    t = np.linspace(0.0, 3.0, 10)
    np.testing.assert_allclose(eci_to_synodic(synodic_to_eci(s, t), t), s, atol=1e-14)


def test_the_moon_at_rest_in_the_synodic_frame_moves_at_one_vu_around_the_earth():
    moon = np.array([[1.0 - MU_EARTH_MOON, 0, 0, 0, 0, 0]])
    eci = synodic_to_eci(moon, 0.4)
    np.testing.assert_allclose(eci[0, :3], [np.cos(0.4), np.sin(0.4), 0.0], atol=1e-15)
    np.testing.assert_allclose(eci[0, 3:], [-np.sin(0.4), np.cos(0.4), 0.0], atol=1e-15)


def test_gauss_is_registered_and_gives_a_cloud_at_the_last_used_time(registry, scenario, rng):
    iod = registry.create("iod", "gauss", n_particles=300)
    assert isinstance(iod, GaussIOD)
    ms = scenario.simulate(rng)
    cloud = iod.estimate(ms, scenario.sensor, rng)
    assert cloud.states.shape == (300, 6)
    assert cloud.epoch == ms.times[cloud.meta["fit_indices"][-1]]


def test_keplerian_iod_misses_the_nrho_truth(scenario):
    """The baseline's point: two-body Gauss puts the truth far outside its own cloud."""
    rng = np.random.default_rng(11)
    cloud = GaussIOD(n_particles=2000).estimate(scenario.simulate(rng), scenario.sensor, rng)
    d = scenario.truth_states(cloud.epoch) - cloud.mean
    assert d @ np.linalg.solve(cloud.covariance, d) > chi2.ppf(0.999, 6)
