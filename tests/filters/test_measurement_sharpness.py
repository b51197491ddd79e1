"""The PGM's response to a measurement far sharper than its cloud: more, smaller components."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.model.belief import ParticleCloud
from cistrack.errors import ParameterError
from cistrack.plugins.filters.pgm.measurement_sharpness import likelihood_ess_fraction, measurement_quadratic
from cistrack.plugins.filters.pgm import PaperPGMFilter, PGMFilter

from .linear_models import LinearDynamics, LinearSensor


def test_measurement_quadratic_is_the_mahalanobis_length_under_the_noise():
    R = np.array([[4.0, 1.0], [1.0, 2.0]])
    r = np.array([[1.0, -2.0], [0.5, 0.0]])
    expected = [v @ np.linalg.solve(R, v) for v in r]
    np.testing.assert_allclose(measurement_quadratic(r, R), expected, rtol=1e-12)


@pytest.mark.parametrize("ratio", [0.1, 1.0, 10.0])
def test_likelihood_ess_fraction_matches_its_closed_form_for_a_gaussian_cloud(ratio):
    # x ~ N(0, s^2), w = exp(-x^2 / (2 sigma^2)): (E w)^2 / E w^2 = sigma sqrt(sigma^2 + 2 s^2) / (sigma^2 + s^2)
    sigma, s = 1.0, ratio
    x = np.random.default_rng(4).normal(0.0, s, 400_000)
    expected = sigma * np.sqrt(sigma**2 + 2 * s**2) / (sigma**2 + s**2)
    assert likelihood_ess_fraction(x**2 / sigma**2) == pytest.approx(expected, rel=0.02)


def test_likelihood_ess_fraction_is_one_over_n_when_one_particle_explains_the_measurement():
    q = np.full(1000, 1e6)
    q[17] = 0.0
    assert likelihood_ess_fraction(q) == pytest.approx(1e-3)


def _wide_cloud(n=10000, seed=5):
    rng = np.random.default_rng(seed)
    m0, P0 = np.zeros(6), np.diag([1.0, 1.0, 1.0, 0.1, 0.1, 0.1])
    P0[0, 3] = P0[3, 0] = 0.2
    return ParticleCloud(rng.multivariate_normal(m0, P0, n), 0.0)


def _update(filt, cloud, sigma, seed=3):
    sensor = LinearSensor(sigma=sigma, coords=(0, 1))
    rng = np.random.default_rng(seed)
    meas = sensor.simulate(np.array([[0.5, -0.3, 0.0, 0.0, 0.0, 0.0]]), np.array([0.0]), rng)[0]
    filt.initialize(cloud, LinearDynamics(), sensor, np.random.default_rng(seed))
    prior_components = filt.belief.mixture.n_components
    filt.update(meas)
    return prior_components, meas, sensor


def test_pgm_splits_its_clusters_at_a_sharp_measurement():
    # sigma 0.005 against a unit-wide cloud: ~0.03% of the particles explain it
    filt = PGMFilter(n_particles=10000, n_components=4, split_components=12)
    prior_m, *_ = _update(filt, _wide_cloud(), sigma=0.005)
    assert prior_m == 4
    assert filt.diagnostics["likelihood_ess_fraction"] < 0.02
    assert filt.diagnostics["n_components"] == 12


def test_pgm_keeps_its_component_count_at_a_measurement_the_particles_resolve():
    filt = PGMFilter(n_particles=10000, n_components=4, split_components=12)
    _update(filt, _wide_cloud(), sigma=0.5)
    assert filt.diagnostics["likelihood_ess_fraction"] > 0.02
    assert filt.diagnostics["n_components"] == 4


def test_split_pgm_update_matches_the_kalman_update_on_a_linear_problem():
    cloud = _wide_cloud()
    filt = PGMFilter(n_particles=10000, n_components=4, split_components=12)
    _, meas, sensor = _update(filt, cloud, sigma=0.005)
    H, R = sensor.H, 0.005 ** 2 * np.eye(2)
    mc, Pc = cloud.mean, cloud.covariance
    K = Pc @ H.T @ np.linalg.inv(H @ Pc @ H.T + R)
    m_ref, P_ref = mc + K @ (meas.z - H @ mc), (np.eye(6) - K @ H) @ Pc
    sd = np.sqrt(np.diag(P_ref))
    b = filt.belief.mixture
    # each k-means cell is a truncated Gaussian treated as a Gaussian (test_linear_gaussian.py)
    assert np.all(np.abs(b.mean - m_ref) / sd < 0.2), (b.mean - m_ref) / sd
    np.testing.assert_allclose(np.sqrt(np.diag(b.covariance)) / sd, 1.0, atol=0.1)


def test_splitting_is_off_by_default_in_pgm_and_pgm_paper():
    assert (PGMFilter().split_components, PGMFilter().split_ess) == (None, 0.02)
    assert PaperPGMFilter().split_components is None


@pytest.mark.parametrize("name, value", [("split_ess", -0.1), ("split_ess", 1.5), ("split_components", -3)])
def test_pgm_rejects_bad_split_settings(name, value):
    with pytest.raises(ParameterError, match=name):
        PGMFilter(**{name: value})
