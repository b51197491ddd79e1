"""The particle-based (ensemble) Kalman update shared by the PGM filter and the EnKF.

Given particles X (N, d) with predicted-measurement residuals D = h(X) - z (N, m) and a
grouping into M components, each component's sample moments give
Pxz = cov(X, D), Pzz = cov(D) + R, K = Pxz Pzz^-1, innovation nu = z - zhat = -mean(D).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cistrack.lazy import lazy_njit
from cistrack.model.belief import regularize_covariance

__all__ = ["GroupMoments", "group_moments", "KalmanGains", "kalman_gains", "gaussian_log_likelihood",
           "component_posterior"]

_LOG_2PI = float(np.log(2.0 * np.pi))

GROUP_BLOCK_ROWS = 131_072
"""A group with more particles than this has its covariance summed over blocks of this many rows
(8 MiB of [x d] each) instead of one block of all its rows: at 1,000,000 particles a large
component's block was the run's peak. Its mean is the same bits either way; its covariance
differs in the last bits (another order of additions). Example 1's default 10,000 particles never
come near it."""


@dataclass
class GroupMoments:
    """Sample moments of each group of particles.

    counts (M,) int; mean_x (M, d); mean_d (M, m); pxx (M, d, d); pxd (M, d, m); pdd (M, m, m).
    Covariances are unbiased (divide by n_i - 1); a group of one particle has zero covariance.
    """

    counts: np.ndarray
    mean_x: np.ndarray
    mean_d: np.ndarray
    pxx: np.ndarray
    pxd: np.ndarray
    pdd: np.ndarray


def group_moments(x: np.ndarray, d: np.ndarray | None, labels: np.ndarray, n_groups: int) -> GroupMoments:
    """Means and (cross-)covariances of ``x`` (N, dx) and ``d`` (N, m) per label in [0, n_groups).

    ``d`` None means no measurement columns (m = 0). One matrix product per group; no loop over
    particles.
    """
    x = np.asarray(x, dtype=float)
    nx = x.shape[1]
    m = 0 if d is None else np.shape(d)[1]
    q = nx + m
    counts = np.bincount(labels, minlength=n_groups)[:n_groups]
    # each group's rows of [x d], in particle order, gathered into one block of its own in turn:
    # the only work array is the largest group's block, not a copy of all N rows
    labels = np.asarray(labels)
    d = np.empty((x.shape[0], 0)) if not m else np.asarray(d, dtype=float)
    means = np.zeros((n_groups, q))
    covs = np.zeros((n_groups, q, q))
    for i in range(n_groups):  # loop over components (few), vectorised over their particles
        if counts[i] > GROUP_BLOCK_ROWS:
            means[i], covs[i] = _large_group_moments(x, d, labels, i, int(counts[i]))
            continue
        yi = np.empty((counts[i], q))
        _gather_group(x, d, labels, i, yi)
        _centre_groups(yi, np.array([0, counts[i]]), means[i:i + 1])  # the mean, and yi centred in place
        if counts[i] > 1:
            covs[i] = (yi.T @ yi) / (yi.shape[0] - 1)
        del yi  # before the next group's block is made
    return GroupMoments(counts, means[:, :nx], means[:, nx:], covs[:, :nx, :nx], covs[:, :nx, nx:],
                        covs[:, nx:, nx:])


def _large_group_moments(x: np.ndarray, d: np.ndarray, labels: np.ndarray, g: int, n: int
                         ) -> tuple[np.ndarray, np.ndarray]:
    """Mean (q,) and unbiased covariance (q, q) of the n (> 1) rows of [x d] labelled ``g``, in
    blocks of at most :data:`GROUP_BLOCK_ROWS` rows: the mean by the same sequential sum as
    :func:`_centre_groups`, the covariance summed block by block."""
    q = x.shape[1] + d.shape[1]
    mean = np.zeros(q)
    _sum_group(x, d, labels, g, mean)
    mean = mean / n
    cov = np.zeros((q, q))
    block = np.empty((min(n, GROUP_BLOCK_ROWS), q))
    start, left = 0, n
    while left > 0:
        k, start = _gather_centred_block(x, d, labels, g, start, mean, block)
        cov += block[:k].T @ block[:k]
        left -= k
    return mean, cov / (n - 1)


@lazy_njit(cache=True)
def _sum_group(x, d, labels, g, acc):
    """acc (q,) += the rows of [x d] labelled ``g``, added one after the other in particle order."""
    nx = x.shape[1]
    for j in range(labels.shape[0]):
        if labels[j] == g:
            for c in range(nx):
                acc[c] += x[j, c]
            for c in range(d.shape[1]):
                acc[nx + c] += d[j, c]


@lazy_njit(cache=True)
def _gather_centred_block(x, d, labels, g, start, mean, out):
    """Up to out.shape[0] rows of [x d] - mean labelled ``g``, from particle ``start`` on, into
    ``out``; returns (rows written, the particle index to continue from)."""
    k = 0
    nx = x.shape[1]
    j = start
    while j < labels.shape[0] and k < out.shape[0]:
        if labels[j] == g:
            for c in range(nx):
                out[k, c] = x[j, c] - mean[c]
            for c in range(d.shape[1]):
                out[k, nx + c] = d[j, c] - mean[nx + c]
            k += 1
        j += 1
    return k, j


@lazy_njit(cache=True)
def _gather_group(x, d, labels, g, out):
    """out (n_g, dx + m) = the rows of [x d] (x (N, dx), d (N, m)) labelled ``g``, in order."""
    k = 0
    nx = x.shape[1]
    for j in range(labels.shape[0]):
        if labels[j] == g:
            for c in range(nx):
                out[k, c] = x[j, c]
            for c in range(d.shape[1]):
                out[k, nx + c] = d[j, c]
            k += 1


@lazy_njit(cache=True)
def _centre_groups(y, edges, means):
    """means[g] (q,) = the mean of rows edges[g]:edges[g+1] of y (R, q), and those rows centred in
    place when there are two or more.

    numpy's ``y[a:b].mean(axis=0)`` bit for bit: for a C-ordered block numpy adds the rows one
    after the other into a zero sum (no pairwise summation across rows) and divides by the count;
    these loops make the same additions in the same order. Compiled because numpy's call took 65
    us per group of 1,700 rows, 6 groups per clustering, 126 times in Example 1."""
    q = y.shape[1]
    for g in range(edges.shape[0] - 1):
        a = edges[g]
        b = edges[g + 1]
        if b <= a:
            continue
        for c in range(q):
            means[g, c] = 0.0
        for i in range(a, b):
            for c in range(q):
                means[g, c] += y[i, c]
        for c in range(q):
            means[g, c] = means[g, c] / (b - a)
        if b - a > 1:
            for i in range(a, b):
                for c in range(q):
                    y[i, c] -= means[g, c]


@dataclass
class KalmanGains:
    """Innovation covariance S (M, m, m), gain K (M, d, m), innovation nu = z - zhat (M, m)."""

    S: np.ndarray
    K: np.ndarray
    nu: np.ndarray


def kalman_gains(moments: GroupMoments, R: np.ndarray) -> KalmanGains:
    """Per-group S = Pzz + R, K = Pxz S^-1 and innovation -mean(D)."""
    S = moments.pdd + R[None]
    S = 0.5 * (S + np.swapaxes(S, -1, -2))
    # K = Pxz S^-1  <=>  S K^T = Pxz^T (S symmetric)
    K = np.swapaxes(np.linalg.solve(S, np.swapaxes(moments.pxd, -1, -2)), -1, -2)
    return KalmanGains(S, K, -moments.mean_d)


def gaussian_log_likelihood(nu: np.ndarray, S: np.ndarray) -> np.ndarray:
    """log N(nu; 0, S) for each group: nu (M, m), S (M, m, m) -> (M,)."""
    L = np.linalg.cholesky(S)
    sol = np.linalg.solve(L, nu[..., None])[..., 0]
    maha = np.sum(sol * sol, axis=-1)
    logdet = 2.0 * np.sum(np.log(np.diagonal(L, axis1=-2, axis2=-1)), axis=-1)
    return -0.5 * (maha + logdet + nu.shape[-1] * _LOG_2PI)


def component_posterior(moments: GroupMoments, gains: KalmanGains) -> tuple[np.ndarray, np.ndarray]:
    """Updated means mu + K nu (M, d) and covariances P - K S K^T (M, d, d), symmetrised and kept
    positive definite."""
    mu = moments.mean_x + np.einsum("mij,mj->mi", gains.K, gains.nu)
    P = moments.pxx - gains.K @ gains.S @ np.swapaxes(gains.K, -1, -2)
    return mu, regularize_covariance(P, 1e-12)
