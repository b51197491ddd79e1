"""The kernel update (plugins/filters/pgm/kernel_update.py): every particle its own Gaussian kernel,
conditioned on one measurement. For a linear measurement each kernel's update is exactly the
Kalman filter's, which is what these tests check against (closed forms written out here)."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.errors import FilterError
from cistrack.interfaces.pgm_steps import ClusteredParticles
from cistrack.plugins.filters.pgm.kernel_update import kernel_update, silverman_factor

H = np.array([[1.0, 0.0, 0.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.5, 0.0, 0.0]])
R = np.diag([0.01, 0.02])
Z = np.array([0.3, -0.2])


def _one_cluster(x: np.ndarray, cov: np.ndarray) -> ClusteredParticles:
    """Particles x (N, 6) as one cluster of covariance cov (6, 6)."""
    return ClusteredParticles(x, np.zeros(x.shape[0], dtype=int), x.mean(axis=0)[None], cov[None])


def _residuals(x: np.ndarray) -> np.ndarray:
    return x @ H.T - Z


def _kalman(mean: np.ndarray, cov: np.ndarray):
    s = H @ cov @ H.T + R
    k = cov @ H.T @ np.linalg.inv(s)
    return mean + k @ (Z - H @ mean), cov - k @ s @ k.T, s


def test_silverman_factor_is_the_textbook_bandwidth():
    assert silverman_factor(1000, 6) == pytest.approx((4.0 / (1000 * 8.0)) ** (2.0 / 10.0))


def test_one_kernel_is_updated_as_the_kalman_filter_does():
    mean = np.array([0.1, 0.0, 0.2, -0.1, 0.0, 0.3])
    cov = np.diag([0.05, 0.04, 0.03, 0.02, 0.02, 0.01])
    samples, _, _, _ = kernel_update(_one_cluster(mean[None], cov), _residuals, R, 40000, np.random.default_rng(0),
                                     "test", bandwidth=1.0)
    m, p, _ = _kalman(mean, cov)
    np.testing.assert_allclose(samples.mean(axis=0), m, atol=4 * np.sqrt(np.diag(p)).max() / np.sqrt(40000))
    np.testing.assert_allclose(np.cov(samples.T), p, atol=0.03 * np.abs(p).max())


def test_kernel_weights_and_evidence_are_the_predictive_likelihoods():
    rng = np.random.default_rng(1)
    x = rng.normal(0.0, 0.3, size=(5, 6))
    cov = np.eye(6) * 0.02
    _, _, log_evidence, w = kernel_update(_one_cluster(x, cov), _residuals, R, 10, np.random.default_rng(2), "test",
                                          bandwidth=0.5)
    s = H @ (0.5 * cov) @ H.T + R
    nu = Z - x @ H.T
    like = np.exp(-0.5 * np.einsum("nm,mk,nk->n", nu, np.linalg.inv(s), nu)) / np.sqrt(np.linalg.det(2 * np.pi * s))
    np.testing.assert_allclose(w, like / like.sum(), rtol=1e-9)
    assert log_evidence == pytest.approx(np.log(like.mean()), rel=1e-9)


def test_draws_are_reproducible_from_the_seed():
    x = np.random.default_rng(3).normal(size=(20, 6))
    args = (_one_cluster(x, np.eye(6)), _residuals, R, 50)
    a = kernel_update(*args, np.random.default_rng(4), "test")[0]
    b = kernel_update(*args, np.random.default_rng(4), "test")[0]
    assert np.array_equal(a, b)


def test_a_non_finite_prediction_is_refused_naming_the_filter():
    def bad(x):
        return np.full((x.shape[0], 2), np.nan)

    with pytest.raises(FilterError, match="pgm-x"):
        kernel_update(_one_cluster(np.zeros((3, 6)), np.eye(6)), bad, R, 5, np.random.default_rng(0), "pgm-x")
