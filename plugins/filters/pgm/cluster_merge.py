"""Merging clusters too small for a full covariance into their nearest neighbour."""
from __future__ import annotations

import numpy as np

__all__ = ["merge_small_clusters", "merged_cluster_targets", "used_ranks", "MERGE_WHOLE_ROWS"]

MERGE_WHOLE_ROWS = 131_072
"""Up to this many particles the scaled coordinates (N, d) are made whole (the numbers Example 1
has always had); above it, the scale and the clusters' means are summed block by block, so that a
merge at 1,000,000 particles makes no (N, d) temporaries (three of them were 144 MB, the run's
peak); the same means to rounding."""


def merge_small_clusters(x: np.ndarray, labels: np.ndarray, min_size: int) -> tuple[np.ndarray, int]:
    """Relabel the particles of every cluster with fewer than ``min_size`` members to the cluster
    whose mean is nearest (in coordinates scaled by the overall standard deviation) among the
    clusters that are large enough; if none is, everything becomes one cluster.

    x (N, d), labels (N,) in [0, M). Returns (labels (N,) in [0, M'), number of clusters merged).
    """
    labels = np.asarray(labels, dtype=np.intp)
    target, merged = merged_cluster_targets(x, labels, min_size)
    return (labels if target is None else target[labels]), merged


def merged_cluster_targets(x: np.ndarray, labels: np.ndarray, min_size: int) -> tuple[np.ndarray | None, int]:
    """What :func:`merge_small_clusters` relabels each cluster to: ``target`` (M,), the new label
    of old label j (None when no cluster is merged), and the number of clusters merged; so that a
    caller that owns ``labels`` (N,) may relabel them in place."""
    m = int(labels.max()) + 1 if labels.size else 0
    counts = np.bincount(labels, minlength=m)
    small = (counts < min_size) & (counts > 0)
    if not small.any():
        return None, 0
    big = np.flatnonzero(counts >= min_size)
    if big.size == 0:
        return np.zeros(m, dtype=np.intp), int(np.count_nonzero(counts)) - 1
    means = _scaled_means(x, labels, counts)
    target = np.arange(m)
    sm = np.flatnonzero(small)
    dist = np.linalg.norm(means[sm][:, None, :] - means[big][None, :, :], axis=2)
    target[sm] = big[np.argmin(dist, axis=1)]
    return used_ranks(target, m)[target], int(sm.size)


def _scaled_means(x: np.ndarray, labels: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """Each cluster's mean (M, d) of ``x`` (N, d) divided by the overall standard deviation of its
    coordinate (a zero deviation counts as 1)."""
    n, d = x.shape
    m = counts.size
    if n <= MERGE_WHOLE_ROWS:
        scale = x.std(axis=0)
        blocks = [(0, n)]
    else:
        blocks = [(a, min(n, a + MERGE_WHOLE_ROWS)) for a in range(0, n, MERGE_WHOLE_ROWS)]
        mean = sum(x[a:b].sum(axis=0) for a, b in blocks) / n
        scale = np.sqrt(sum(((x[a:b] - mean) ** 2).sum(axis=0) for a, b in blocks) / n)
    scale[~(scale > 0)] = 1.0
    means = np.zeros((m, d))
    for a, b in blocks:
        z = x[a:b] / scale
        for j in range(d):  # loop over coordinates, vectorised over particles
            means[:, j] += np.bincount(labels[a:b], weights=z[:, j], minlength=m)
    return means / np.maximum(counts, 1)[:, None]


def used_ranks(labels: np.ndarray, m: int = 0) -> np.ndarray:
    """For each label value j < max(m, labels.max() + 1), its rank among the values ``labels`` (N,)
    uses (np.unique's inverse as a lookup table (M,), without its sort); unused values map to the
    rank of the next used one below them."""
    return np.cumsum(np.bincount(labels, minlength=m) > 0) - 1
