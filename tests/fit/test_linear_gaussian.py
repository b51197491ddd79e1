"""On a linear-Gaussian problem (force-free particle, linear sensor) the fit is the closed-form
weighted least-squares solution and its covariance is the inverse Fisher information."""
from __future__ import annotations

import numpy as np

from cistrack.least_squares import fit_orbit

from .linear_components import FreeParticle, LinearSensor, free_particle_stm

TIMES = np.linspace(-2.0, 3.0, 11)
T0 = 0.5
TRUTH = np.array([0.3, -0.2, 0.1, 0.01, 0.02, -0.03])


def _problem(seed: int = 3):
    dyn, sen = FreeParticle(), LinearSensor()
    truth = np.array([TRUTH @ free_particle_stm(t - T0).T for t in TIMES])
    ms = sen.simulate(truth, TIMES, np.random.default_rng(seed))
    rows = np.vstack([sen.matrix @ free_particle_stm(t - T0) for t in TIMES])   # (3K, 6)
    weights = 1.0 / ms.sigmas.reshape(-1) ** 2
    fisher = rows.T @ (weights[:, None] * rows)
    return dyn, sen, ms, rows, weights, fisher


def test_covariance_equals_the_inverse_fisher_information():
    dyn, sen, ms, _, _, fisher = _problem()
    res = fit_orbit(dyn, sen, ms, np.zeros(6), T0)
    np.testing.assert_allclose(res.covariance, np.linalg.inv(fisher), rtol=1e-7, atol=0)


def test_estimate_equals_the_closed_form_weighted_least_squares_solution():
    dyn, sen, ms, rows, weights, fisher = _problem()
    res = fit_orbit(dyn, sen, ms, np.zeros(6), T0)
    want = np.linalg.solve(fisher, rows.T @ (weights * ms.values.reshape(-1)))
    assert np.all(np.abs(res.state - want) < FLOOR_SIGMAS * np.sqrt(np.diag(res.covariance)))
    assert res.converged


FLOOR_SIGMAS = 1e-4
"""How close, in sigmas, the iteration can come to the closed form: a residual in sigmas
(value ~0.3, sigma 1e-6) carries a rounding error of about 2.2e-16 * 0.3 / 1e-6 = 7e-11, so the
cost (~33 for 33 components) is known to ~1e-9, and a step of s sigmas lowers it by s^2: steps
under ~3e-5 sigma are beneath the cost's floor, where the fit stops (the stop's rule,
``stall_step``, is 1e-2 sigma). Machines differ in those last bits (4e-6 sigma on one, under
1e-6 on another)."""


def test_a_prior_adds_its_information_and_pulls_the_estimate_to_the_closed_form_map():
    dyn, sen, ms, rows, weights, fisher = _problem()
    p0 = np.diag([1e-9, 1e-9, 1e-9, 1e-11, 1e-11, 1e-11])   # as informative as the data
    m0 = TRUTH + 1e-5
    res = fit_orbit(dyn, sen, ms, np.zeros(6), T0, prior=(m0, p0))
    info = fisher + np.linalg.inv(p0)
    want = np.linalg.solve(info, rows.T @ (weights * ms.values.reshape(-1)) + np.linalg.solve(p0, m0))
    np.testing.assert_allclose(res.covariance, np.linalg.inv(info), rtol=1e-7, atol=0)
    assert np.all(np.abs(res.state - want) < 1e-6 * np.sqrt(np.diag(res.covariance)))


def test_noise_scale_is_the_root_of_chi2_over_the_degrees_of_freedom():
    dyn, sen, ms, *_ = _problem()
    res = fit_orbit(dyn, sen, ms, np.zeros(6), T0)
    assert res.n_used == len(ms) and res.n_rejected == 0
    assert np.isclose(res.noise_scale, np.sqrt(res.chi2 / (3 * len(ms) - 6)))
    assert np.isclose(res.rms, np.sqrt(res.chi2 / (3 * len(ms))))
