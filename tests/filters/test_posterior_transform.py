"""Shape-keeping posterior particles of the PGM (posterior_transform.py, posterior_draw = "transform")."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import skew

from cistrack.model.belief import GaussianMixture, ParticleCloud
from cistrack.errors import ParameterError
from cistrack.plugins.filters.pgm import PGMFilter
from cistrack.plugins.filters.pgm.posterior_transform import moment_map, transform_clusters

from .linear_models import LinearDynamics, LinearSensor, filter_beside_kalman


def _spd(seed, d=6):
    a = np.random.default_rng(seed).normal(size=(d, d))
    return a @ a.T + 0.1 * np.eye(d)


def test_moment_map_takes_the_prior_covariance_to_the_posterior():
    s, p = _spd(0), _spd(1)
    a = moment_map(s, p)
    np.testing.assert_allclose(a @ s @ a.T, p, rtol=1e-9, atol=1e-12)


def test_moment_map_is_the_identity_when_nothing_was_learned():
    s = _spd(2)
    np.testing.assert_allclose(moment_map(s, s), np.eye(6), atol=1e-10)


def test_moment_map_scales_uniformly_for_a_scaled_covariance():
    s = _spd(3)
    np.testing.assert_allclose(moment_map(s, 0.25 * s), 0.5 * np.eye(6), atol=1e-10)


def test_one_cluster_kept_whole_gets_exactly_the_posterior_moments():
    rng = np.random.default_rng(4)
    x = rng.standard_exponential((5000, 6)) @ _spd(5)  # skewed, correlated
    labels = np.zeros(5000, dtype=np.intp)
    m, s = x.mean(axis=0), np.cov(x.T)
    post = GaussianMixture(np.ones(1), (m + 1.0)[None], _spd(6)[None])
    y, lab = transform_clusters(x, labels, m[None], s[None], post, 5000, rng)
    np.testing.assert_allclose(y.mean(axis=0), m + 1.0, atol=1e-9)
    np.testing.assert_allclose(np.cov(y.T), _spd(6), rtol=1e-8, atol=1e-10)
    assert np.all(lab == 0)


def test_components_get_as_many_particles_as_their_weight_asks_without_duplicates():
    rng = np.random.default_rng(7)
    x = np.concatenate([rng.normal(size=(300, 6)), rng.normal(size=(700, 6)) + 5.0])
    labels = np.repeat([0, 1], [300, 700])
    means = np.stack([x[:300].mean(0), x[300:].mean(0)])
    covs = np.stack([np.cov(x[:300].T), np.cov(x[300:].T)])
    post = GaussianMixture(np.array([0.9, 0.1]), means, covs)
    y, lab = transform_clusters(x, labels, means, covs, post, 1000, rng)
    assert abs(np.count_nonzero(lab == 0) - 900) < 60  # multinomial(1000, 0.9): sd 9.5
    assert np.unique(y, axis=0).shape[0] == 1000


def test_an_uninformative_update_keeps_a_skewed_cloud_skewed():
    def final_skew(draw):
        rng = np.random.default_rng(8)
        cloud = ParticleCloud(rng.standard_exponential((10000, 6)) * 0.1, 0.0)
        sensor = LinearSensor(sigma=1e3, coords=(0,))  # far wider than the cloud
        ms = sensor.simulate(np.zeros((1, 6)), np.array([1e-3]), rng)
        filt = PGMFilter(n_particles=10000, n_components=1, posterior_draw=draw)
        filt.initialize(cloud, LinearDynamics(), sensor, np.random.default_rng(9))
        filt.predict(ms[0].t)
        filt.update(ms[0])
        return skew(filt.belief.samples.states[:, 1])
    assert final_skew("transform") > 1.5  # an exponential's skewness is 2
    assert abs(final_skew("gaussian")) < 0.1


def test_one_component_pgm_with_transformed_particles_is_the_kalman_filter():
    sigma = 0.02
    m0 = np.array([1.0, 2.0, -0.5, 0.1, -0.1, 0.05])
    p0 = np.diag([0.5, 0.5, 0.5, 0.05, 0.05, 0.05])
    times = np.arange(1, 11) * 0.3
    sensor = LinearSensor(sigma=sigma, coords=(0, 4))
    filt = PGMFilter(n_particles=5000, n_components=1, posterior_draw="transform")
    m, P = filter_beside_kalman(filt, m0, p0, times, sensor, np.random.default_rng(10),
                                np.random.default_rng(11))
    x = filt.belief.samples.states
    np.testing.assert_allclose(x.mean(axis=0), m, atol=1e-9)
    np.testing.assert_allclose(np.cov(x.T), P, rtol=1e-6, atol=1e-12)


def test_an_unknown_posterior_draw_is_refused_by_name():
    with pytest.raises(ParameterError, match="posterior_draw"):
        PGMFilter(posterior_draw="kde")
