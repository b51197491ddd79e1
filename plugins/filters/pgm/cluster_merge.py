"""Merging clusters too small for a full covariance into their nearest neighbour."""
from __future__ import annotations

import numpy as np

__all__ = ["merge_small_clusters"]


def merge_small_clusters(x: np.ndarray, labels: np.ndarray, min_size: int) -> tuple[np.ndarray, int]:
    """Relabel the particles of every cluster with fewer than ``min_size`` members to the cluster
    whose mean is nearest (in coordinates scaled by the overall standard deviation) among the
    clusters that are large enough; if none is, everything becomes one cluster.

    x (N, d), labels (N,) in [0, M). Returns (labels (N,) in [0, M'), number of clusters merged).
    """
    labels = np.asarray(labels, dtype=np.intp)
    m = int(labels.max()) + 1 if labels.size else 0
    counts = np.bincount(labels, minlength=m)
    small = (counts < min_size) & (counts > 0)
    if not small.any():
        return labels, 0
    big = np.flatnonzero(counts >= min_size)
    if big.size == 0:
        return np.zeros_like(labels), int(np.count_nonzero(counts)) - 1
    scale = x.std(axis=0)
    scale[~(scale > 0)] = 1.0
    z = x / scale
    means = np.zeros((m, x.shape[1]))
    for j in range(x.shape[1]):  # loop over coordinates, vectorised over particles
        means[:, j] = np.bincount(labels, weights=z[:, j], minlength=m)
    means /= np.maximum(counts, 1)[:, None]
    target = np.arange(m)
    sm = np.flatnonzero(small)
    dist = np.linalg.norm(means[sm][:, None, :] - means[big][None, :, :], axis=2)
    target[sm] = big[np.argmin(dist, axis=1)]
    target = np.cumsum(np.bincount(target, minlength=m) > 0)[target] - 1  # np.unique's inverse, without its sort
    return target[labels].astype(np.intp, copy=False), int(sm.size)
