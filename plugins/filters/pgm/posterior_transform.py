"""Posterior particles that keep their clusters' shapes (the PGM's ``posterior_draw = "transform"``).

The plain PGM draws its N posterior particles from the Gaussian mixture. Each component then
forgets the shape its cluster had: a curved or heavy-tailed cloud becomes a set of Gaussians with
Gaussian tails. Early in a track, when the cloud is long in range and curved, the exact posterior is far from
Gaussian (docs/history/pgm.md).

Here every cluster's particles are carried into the posterior instead. Cluster i, with sample
mean m_i and covariance S_i = L L^T, is mapped affinely onto its component's posterior
(mu_i+, P_i+):

    x -> mu_i+ + A_i (x - m_i),   A_i = L B^(1/2) L^-1,   B = L^-1 P_i+ L^-T,

so the mapped cluster has exactly the posterior mean and covariance. In the cluster's whitened
coordinates A_i is symmetric (no rotation), so the cloud's non-Gaussian features keep their
directions. This is the deterministic square-root form of the ensemble Kalman update, applied
per component. With one component on a linear-Gaussian problem it reproduces the Kalman filter
exactly (tests/filters/test_posterior_transform.py).

The component weights decide how many particles each component keeps: N_i ~ multinomial(N, w+).
A component that keeps fewer than its cluster holds keeps a random subset. One that asks for more
gets the rest as Gaussian draws from its posterior, so no particle is ever duplicated: duplicates
would stay duplicates under deterministic propagation.

Measurements: docs/history/pgm.md and docs/calibration.md.
"""
from __future__ import annotations

import numpy as np

from cistrack.model.belief import GaussianMixture

__all__ = ["moment_map", "transform_clusters"]


def moment_map(prior_cov: np.ndarray, post_cov: np.ndarray) -> np.ndarray:
    """A (d, d) with A S A^T = P for S = ``prior_cov``, P = ``post_cov`` (both (d, d), positive
    definite), symmetric in the whitened coordinates of S (A = I when P = S)."""
    lo = np.linalg.cholesky(prior_cov)
    li = np.linalg.inv(lo)
    b = li @ post_cov @ li.T
    ev, vec = np.linalg.eigh(0.5 * (b + b.T))
    return lo @ (vec * np.sqrt(np.maximum(ev, 0.0))) @ vec.T @ li


def transform_clusters(x: np.ndarray, labels: np.ndarray, cluster_means: np.ndarray,
                       cluster_covs: np.ndarray, post: GaussianMixture, n: int,
                       rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """``n`` posterior particles (n, d) and their component labels (n,).

    x (N, d) and labels (N,) in [0, M): the clustered prior particles; cluster_means (M, d) and
    cluster_covs (M, d, d): their sample moments per cluster; post: the posterior mixture of M
    components (see the module docstring).
    """
    counts = rng.multinomial(n, post.weights)
    xs, ls = [], []
    for c, nc in enumerate(counts):
        if nc == 0:
            continue
        idx = np.flatnonzero(labels == c)
        keep = idx if nc >= idx.size else rng.choice(idx, size=nc, replace=False)
        a = moment_map(cluster_covs[c], post.covariances[c])
        y = post.means[c] + (x[keep] - cluster_means[c]) @ a.T
        if nc > idx.size:
            y = np.concatenate([y, rng.multivariate_normal(post.means[c], post.covariances[c],
                                                           size=nc - idx.size)])
        xs.append(y)
        ls.append(np.full(nc, c, dtype=np.intp))
    return np.concatenate(xs), np.concatenate(ls)
