"""On a linear-Gaussian problem every filter must reproduce the exact Kalman filter."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.model.belief import ParticleCloud
from cistrack.plugins.clustering.kmeans import KMeansClusterer
from cistrack.plugins.filters.enkf import EnKFFilter
from cistrack.plugins.filters.pgm import PGMFilter
from cistrack.plugins.filters.sir import SIRFilter
from cistrack.plugins.filters.ukf import UKFFilter

from .linear_models import LinearDynamics, LinearSensor, transition

M0 = np.array([1.0, 2.0, -0.5, 0.1, -0.1, 0.05])
P0 = np.diag([0.5, 0.5, 0.5, 0.05, 0.05, 0.05])
P0[0, 3] = P0[3, 0] = 0.03
TIMES = [0.5, 1.0, 1.5, 2.0]
SIGMA = 0.2


def exact_kalman(m, P, H, R, times, zs):
    """Textbook Kalman filter, written out independently of the filters under test."""
    t_prev = 0.0
    for t, z in zip(times, zs):
        F = transition(t - t_prev)
        m, P = F @ m, F @ P @ F.T
        S = H @ P @ H.T + R
        K = P @ H.T @ np.linalg.inv(S)
        m = m + K @ (z - H @ m)
        P = (np.eye(6) - K @ H) @ P
        t_prev = t
    return m, P


@pytest.fixture(scope="module")
def problem():
    rng = np.random.default_rng(42)
    sensor = LinearSensor(sigma=SIGMA, coords=(0, 1, 2))
    truth0 = rng.multivariate_normal(M0, P0)
    truth = np.stack([transition(t) @ truth0 for t in TIMES])
    ms = sensor.simulate(truth, np.array(TIMES), rng)
    cloud = ParticleCloud(rng.multivariate_normal(M0, P0, 40000), 0.0)
    # the reference starts from the moments of the cloud every filter is given
    m, P = exact_kalman(cloud.mean, cloud.covariance, sensor.H, SIGMA**2 * np.eye(3), TIMES, ms.values)
    return sensor, ms, cloud, m, P


def run_filter(filt, problem, seed=7):
    sensor, ms, cloud, _, _ = problem
    filt.initialize(cloud, LinearDynamics(), sensor, np.random.default_rng(seed))
    for meas in ms:
        filt.predict(meas.t)
        filt.update(meas)
    return filt.belief


def assert_matches_kalman(belief, m, P, mean_tol, cov_tol):
    sd = np.sqrt(np.diag(P))
    mean = belief.mixture.mean
    cov = belief.mixture.covariance
    assert np.all(np.abs(mean - m) / sd < mean_tol), (mean - m) / sd
    assert np.all(np.abs(np.sqrt(np.diag(cov)) / sd - 1.0) < cov_tol), np.sqrt(np.diag(cov)) / sd


def test_ukf_equals_the_kalman_filter_on_a_linear_problem(problem):
    *_, m, P = problem
    belief = run_filter(UKFFilter(), problem)
    np.testing.assert_allclose(belief.mixture.means[0], m, rtol=0, atol=1e-9 * np.sqrt(np.diag(P)).max())
    np.testing.assert_allclose(belief.mixture.covariances[0], P, rtol=1e-8, atol=1e-12)


def test_pgm_with_one_component_matches_the_kalman_filter(problem):
    *_, m, P = problem
    belief = run_filter(PGMFilter(n_particles=10000, n_components=1), problem)
    assert belief.mixture.n_components == 1
    # Monte Carlo error of a 10,000-sample mean is 0.01 sigma per step, of a sigma ~0.7 %
    assert_matches_kalman(belief, m, P, mean_tol=0.08, cov_tol=0.06)


def test_pgm_with_several_components_matches_the_kalman_filter_after_one_update(problem):
    sensor, ms, cloud, _, _ = problem
    m, P = exact_kalman(cloud.mean, cloud.covariance, sensor.H, SIGMA**2 * np.eye(3), TIMES[:1], ms.values[:1])
    filt = PGMFilter(n_particles=10000, n_components=5)
    filt.initialize(cloud, LinearDynamics(), sensor, np.random.default_rng(3))
    filt.predict(ms[0].t)
    filt.update(ms[0])
    assert filt.belief.mixture.n_components == 5
    assert_matches_kalman(filt.belief, m, P, mean_tol=0.2, cov_tol=0.1)


def test_pgm_with_several_components_stays_close_to_the_kalman_filter_over_several_updates(problem):
    # Each k-means cell is a truncated piece of a Gaussian that the filter treats as a Gaussian;
    # that approximation (not Monte Carlo noise: it stays with 4x the particles) costs about
    # 0.1 sigma of mean per update in this problem.
    *_, m, P = problem
    belief = run_filter(PGMFilter(n_particles=10000, n_components=5), problem)
    assert belief.mixture.n_components == 5
    assert_matches_kalman(belief, m, P, mean_tol=0.5, cov_tol=0.12)


def test_pgm_gives_its_n_components_to_a_clusterer_instance_left_at_its_default(problem):
    # (a clusterer whose own n_components contradicts the filter's is refused: test_pgm_clusterer.py)
    clusterer = KMeansClusterer()
    filt = PGMFilter(n_particles=4000, n_components=3, clusterer=clusterer)
    belief = run_filter(filt, problem)
    assert belief.mixture.n_components == 3
    assert clusterer.n_components == KMeansClusterer().n_components  # the caller's instance is left alone


def test_enkf_matches_the_kalman_filter(problem):
    *_, m, P = problem
    belief = run_filter(EnKFFilter(n_particles=4000), problem)
    assert_matches_kalman(belief, m, P, mean_tol=0.12, cov_tol=0.1)


def test_sir_matches_the_kalman_filter_after_one_update(problem):
    sensor, ms, cloud, _, _ = problem
    m, P = exact_kalman(cloud.mean, cloud.covariance, sensor.H, SIGMA**2 * np.eye(3), TIMES[:1], ms.values[:1])
    filt = SIRFilter(n_particles=40000)
    filt.initialize(cloud, LinearDynamics(), sensor, np.random.default_rng(3))
    filt.predict(ms[0].t)
    filt.update(ms[0])
    assert_matches_kalman(filt.belief, m, P, mean_tol=0.15, cov_tol=0.1)


def test_sir_depletes_its_particles_over_updates_without_process_noise(problem):
    filt = SIRFilter(n_particles=20000)
    run_filter(filt, problem)
    assert filt.diagnostics["unique_particles"] < 0.2 * 20000
    assert filt.diagnostics["ess_before_resampling"] < 0.5 * 20000
