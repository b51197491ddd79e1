"""The fitted state and covariance carried to other times: Phi P Phi^T (exact on linear dynamics),
and the covariance shrinks inside the arc relative to a long prediction beyond it."""
from __future__ import annotations

import numpy as np

from cistrack.least_squares import fit_orbit, predict

from .arcs import GUESS_OFFSET, cr3bp_arc
from .linear_components import FreeParticle, LinearSensor, free_particle_stm


def test_predicted_covariance_is_phi_p_phi_transpose_on_linear_dynamics():
    dyn, sen = FreeParticle(), LinearSensor()
    times = np.linspace(0.0, 2.0, 6)
    ms = sen.simulate(np.zeros((6, 6)), times, np.random.default_rng(2))
    res = fit_orbit(dyn, sen, ms, np.zeros(6), 1.0)
    states, cov = predict(res, dyn, np.array([-1.0, 1.0, 5.0]))
    for k, t in enumerate((-1.0, 1.0, 5.0)):
        phi = free_particle_stm(t - 1.0)
        np.testing.assert_allclose(cov[k], phi @ res.covariance @ phi.T, rtol=1e-6, atol=1e-30)
        np.testing.assert_allclose(states[k], phi @ res.state, atol=1e-12)


def test_prediction_at_the_observation_times_matches_the_truth_within_its_covariance():
    arc = cr3bp_arc()
    res = fit_orbit(arc.dynamics, arc.sensor, arc.noisy(2), arc.truth0 + GUESS_OFFSET, 0.0)
    states, cov = predict(res, arc.dynamics, arc.times)
    m2 = [e @ np.linalg.solve(c, e) for e, c in zip(arc.truth - states, cov)]
    assert max(m2) < 16.81
