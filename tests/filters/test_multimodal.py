"""A bimodal prior: the PGM filter keeps both modes and moves the weight to the one the
measurement favours; a single Gaussian cannot represent such a prior."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.model.belief import ParticleCloud
from cistrack.model.measurement import Measurement
from cistrack.plugins.filters.pgm import PGMFilter
from cistrack.plugins.filters.ukf import UKFFilter

from .linear_models import LinearDynamics, LinearSensor

MODE_A = np.array([-3.0, 0.0, 0.0, 0.0, 0.0, 0.0])
MODE_B = np.array([3.0, 0.0, 0.0, 0.0, 0.0, 0.0])
P_MODE = np.diag([0.2, 0.2, 0.2, 0.01, 0.01, 0.01])


@pytest.fixture(scope="module")
def bimodal_cloud():
    rng = np.random.default_rng(5)
    x = np.vstack([rng.multivariate_normal(MODE_A, P_MODE, 3000), rng.multivariate_normal(MODE_B, P_MODE, 3000)])
    return ParticleCloud(x, 0.0)


def weight_near(mixture, centre):
    near = np.linalg.norm(mixture.means[:, :3] - centre[:3], axis=1) < 1.5
    return float(mixture.weights[near].sum())


def test_pgm_prior_has_components_on_both_modes(bimodal_cloud):
    filt = PGMFilter(n_particles=6000, n_components=4)
    filt.initialize(bimodal_cloud, LinearDynamics(), LinearSensor(sigma=0.3), np.random.default_rng(0))
    mix = filt.belief.mixture
    assert weight_near(mix, MODE_A) == pytest.approx(0.5, abs=0.02)
    assert weight_near(mix, MODE_B) == pytest.approx(0.5, abs=0.02)


def test_pgm_moves_the_weight_to_the_mode_the_measurement_favours(bimodal_cloud):
    sensor = LinearSensor(sigma=0.3)
    filt = PGMFilter(n_particles=6000, n_components=4)
    filt.initialize(bimodal_cloud, LinearDynamics(), sensor, np.random.default_rng(0))
    filt.update(Measurement(0.0, np.array([2.8, 0.1]), 0.09 * np.eye(2), sensor.names))
    post = filt.belief
    assert weight_near(post.mixture, MODE_B) > 0.999
    assert np.mean(post.samples.states[:, 0] > 0) > 0.99
    assert np.all(np.isfinite(post.mixture.covariances))


def test_a_single_gaussian_filter_puts_its_mean_where_the_prior_has_no_mass(bimodal_cloud):
    filt = UKFFilter()
    filt.initialize(bimodal_cloud, LinearDynamics(), LinearSensor(sigma=0.3), np.random.default_rng(0))
    mix = filt.belief.mixture
    assert mix.n_components == 1
    # the moment-matched mean sits between the modes, 6 sigma of a mode away from either
    mean_x = mix.means[0, 0]
    assert abs(mean_x - MODE_A[0]) > 6 * np.sqrt(P_MODE[0, 0])
    assert abs(mean_x - MODE_B[0]) > 6 * np.sqrt(P_MODE[0, 0])
    assert np.mean(np.abs(bimodal_cloud.states[:, 0] - mean_x) < 1.5) < 0.01
    # and the prior's own particles are less probable under it than under the PGM mixture
    pgm = PGMFilter(n_particles=6000, n_components=4)
    pgm.initialize(bimodal_cloud, LinearDynamics(), LinearSensor(sigma=0.3), np.random.default_rng(0))
    x = bimodal_cloud.states
    assert np.mean(pgm.belief.mixture.logpdf(x)) > np.mean(mix.logpdf(x)) + 0.5
