"""The PGM's sigma points are filterpy's MerweScaledSigmaPoints, bit for bit, without importing
filterpy (issue 15: filterpy.kalman costs ~0.7 s of CPU at start-up)."""
from __future__ import annotations

import numpy as np
import pytest
from filterpy.kalman import MerweScaledSigmaPoints

from cistrack.plugins.filters.sigma_points import MerweSigmaPoints


@pytest.mark.parametrize("alpha, beta, kappa", [(1.0, 2.0, 0.0), (1e-3, 2.0, 0.0), (0.5, 2.0, 3.0 - 6)])
@pytest.mark.parametrize("seed", range(5))
def test_points_and_weights_equal_filterpys(alpha, beta, kappa, seed):
    g = np.random.default_rng(seed)
    a = g.normal(size=(6, 6)) * np.array([1e-3, 1e-3, 1e-3, 1e-5, 1e-5, 1e-5])
    P = a @ a.T + 1e-14 * np.eye(6)
    x = g.normal(size=6)
    ours, theirs = MerweSigmaPoints(6, alpha, beta, kappa), MerweScaledSigmaPoints(6, alpha, beta, kappa)
    assert np.array_equal(ours.sigma_points(x, P), theirs.sigma_points(x, P))
    assert np.array_equal(ours.Wm, theirs.Wm) and np.array_equal(ours.Wc, theirs.Wc)
    assert ours.num_sigmas() == theirs.num_sigmas() == 13


def test_points_reproduce_the_mean_and_covariance():
    P = np.diag([4.0, 1.0, 0.25])
    x = np.array([1.0, -2.0, 3.0])
    pts = MerweSigmaPoints(3, 1.0, 2.0, 0.0)
    s = pts.sigma_points(x, P)
    mean = pts.Wm @ s
    dev = s - mean
    assert np.allclose(mean, x, rtol=0, atol=1e-14)
    assert np.allclose((dev.T * pts.Wc) @ dev, P, rtol=0, atol=1e-13)


def test_points_of_several_gaussians_at_once_are_each_ones_points():
    g = np.random.default_rng(11)
    a = g.normal(size=(4, 6, 6)) * np.array([1e-3, 1e-3, 1e-3, 1e-5, 1e-5, 1e-5])
    P = a @ np.swapaxes(a, 1, 2) + 1e-14 * np.eye(6)
    x = g.normal(size=(4, 6))
    pts = MerweSigmaPoints(6, 1.0, 2.0, 0.0)
    batch = pts.sigma_points_batch(x, P)
    assert batch.shape == (4, 13, 6)
    assert all(np.array_equal(batch[i], pts.sigma_points(x[i], P[i])) for i in range(4))
