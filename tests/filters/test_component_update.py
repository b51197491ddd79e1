"""The PGM's per-component measurement updates against independent references: the exact Kalman
update and evidence of each component (linear h), and a posterior by quadrature on a grid (a
bearing measured far more precisely than a component's spread)."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.errors import ParameterError
from cistrack.plugins.filters.pgm.component_update import ensemble_component_update, iterated_component_update
from cistrack.plugins.filters.kalman_update import group_moments
from cistrack.plugins.filters.pgm import PGMFilter

from .test_posterior_linearization import P0_BEARING, SIGMA, X0, _bearing_residual, _expected_nees, _grid_posterior


def _random_components(rng, m, d):
    a = rng.standard_normal((m, d, d))
    return rng.standard_normal((m, d)), a @ np.swapaxes(a, 1, 2) + 0.1 * np.eye(d)


@pytest.mark.parametrize("likelihood", ["posterior", "prior"])
def test_linear_measurement_gives_each_component_its_exact_kalman_update_and_evidence(likelihood):
    rng = np.random.default_rng(5)
    means, covs = _random_components(rng, 3, 4)
    H = rng.standard_normal((2, 4))
    R = np.diag([0.05, 0.2])
    z = rng.standard_normal(2)
    mu, P, loglik = iterated_component_update(means, covs, lambda X: X @ H.T - z, R, likelihood=likelihood)
    for i in range(3):
        S = H @ covs[i] @ H.T + R
        K = covs[i] @ H.T @ np.linalg.inv(S)
        nu = z - H @ means[i]
        np.testing.assert_allclose(mu[i], means[i] + K @ nu, rtol=1e-7, atol=1e-9)
        np.testing.assert_allclose(P[i], covs[i] - K @ S @ K.T, rtol=1e-7, atol=1e-9)
        expected = -0.5 * (nu @ np.linalg.solve(S, nu) + np.log(np.linalg.det(2 * np.pi * S)))
        assert loglik[i] == pytest.approx(expected, rel=1e-9)


def _bearing_cloud_moments(n=20000):
    x = np.random.default_rng(8).multivariate_normal(X0, P0_BEARING, n)
    return group_moments(x, _bearing_residual(x), np.zeros(n, dtype=np.intp), 1)


def test_iterated_component_update_covers_the_true_posterior_of_a_precise_bearing():
    m_true, P_true = _grid_posterior()
    mom = _bearing_cloud_moments()
    mu, P, _ = iterated_component_update(mom.mean_x, mom.pxx, _bearing_residual, np.array([[SIGMA ** 2]]),
                                         max_iterations=20)
    assert _expected_nees(mu[0], P[0], m_true, P_true) == pytest.approx(2.0, abs=0.5)


def test_ensemble_component_update_barely_uses_a_precise_bearing():
    # the paper's update regresses h over the whole wide component: the curvature lands in the
    # innovation covariance and the posterior stays almost as wide as the prior
    m_true, P_true = _grid_posterior()
    mu, P, _ = ensemble_component_update(_bearing_cloud_moments(), np.array([[SIGMA ** 2]]))
    assert np.linalg.det(P[0]) > 100.0 * np.linalg.det(P_true)


def test_pgm_defaults_to_the_iterated_component_update_with_kmeans_clusters():
    f = PGMFilter()
    assert (f.component_update, f.clusterer) == ("iterated", "kmeans")


def test_pgm_paper_is_the_papers_plain_pgm():
    from cistrack.plugin.registry import default_registry
    f = default_registry().create("filter", "pgm-paper")
    assert f.component_update == "ensemble"
    assert f.clusterer == "kmeans"


@pytest.mark.parametrize("name, value", [("component_update", "ukf"), ("component_likelihood", "both"),
                                         ("update_iterations", 0)])
def test_pgm_rejects_bad_update_settings(name, value):
    with pytest.raises(ParameterError, match=name):
        PGMFilter(**{name: value})


def _cloud_with_an_outlying_group(n_small: int):
    from cistrack.model.belief import ParticleCloud
    rng = np.random.default_rng(2)
    x = rng.standard_normal((1000, 6)) * 1e-3
    x[:n_small] += 0.05                       # a small, well separated group
    return ParticleCloud(x, 0.0)


@pytest.mark.parametrize("n_small, merged", [(20, True), (60, False)])
def test_pgm_merges_clusters_below_three_percent_of_its_particles(n_small, merged):
    # 3% of 1,000 particles = 30: a 6-D covariance from 20 particles is too narrow to trust
    from .linear_models import LinearDynamics, LinearSensor
    filt = PGMFilter(n_particles=1000, n_components=2)
    filt.initialize(_cloud_with_an_outlying_group(n_small), LinearDynamics(), LinearSensor(sigma=1.0, coords=(0,)),
                    np.random.default_rng(3))
    assert filt.belief.mixture.n_components == (1 if merged else 2)


def test_pgm_paper_keeps_clusters_down_to_twice_the_dimension():
    from .linear_models import LinearDynamics, LinearSensor
    from cistrack.plugins.filters.pgm import PaperPGMFilter
    filt = PaperPGMFilter(n_particles=1000, n_components=2)
    filt.initialize(_cloud_with_an_outlying_group(20), LinearDynamics(), LinearSensor(sigma=1.0, coords=(0,)),
                    np.random.default_rng(3))
    assert filt.belief.mixture.n_components == 2
