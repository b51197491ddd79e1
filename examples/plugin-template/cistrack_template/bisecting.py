"""Bisecting clustering: split the widest cluster in two along its principal axis, repeat."""
from __future__ import annotations

import numpy as np

from cistrack.api import Clusterer, ParameterError, check_int

__all__ = ["BisectingClusterer"]


class BisectingClusterer(Clusterer):
    """Deterministic divisive clustering on standardised coordinates.

    Starting from one cluster, the cluster with the largest scatter (sum of squared distances
    to its mean) is split by the hyperplane through its mean normal to its principal axis,
    until there are ``n_components`` clusters or no cluster of at least ``min_size`` particles
    can be split.

    Parameters
    ----------
    n_components : int
        Number of clusters wanted (M).
    min_size : int
        Smallest cluster that may be split (and smallest half a split may leave).
    """

    def __init__(self, n_components: int = 6, min_size: int = 13):
        self.n_components = check_int(self, "n_components", n_components, minimum=1)
        self.min_size = check_int(self, "min_size", min_size, minimum=2)

    def cluster(self, x: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Labels (N,) int in [0, M) for particles ``x`` (N, d); ``rng`` is not needed."""
        x = np.asarray(x, dtype=float)
        if x.ndim != 2 or x.shape[0] == 0 or not np.all(np.isfinite(x)):
            raise ParameterError(f"{self._label()}: particles must be a finite (N, d) array with N >= 1, "
                                 f"got shape {np.shape(x)}")
        scale = x.std(axis=0)
        z = (x - x.mean(axis=0)) / np.where(scale > 0, scale, 1.0)
        labels = np.zeros(x.shape[0], dtype=np.intp)
        frozen: set[int] = set()
        for new in range(1, self.n_components):  # loop over clusters, vectorised over particles
            k = self._widest(z, labels, new, frozen)
            if k is None:
                break
            sel = np.flatnonzero(labels == k)
            d = z[sel] - z[sel].mean(axis=0)
            _, _, vt = np.linalg.svd(d, full_matrices=False)
            side = d @ vt[0] > 0.0
            if min(side.sum(), (~side).sum()) < self.min_size // 2:
                frozen.add(k)
                continue
            labels[sel[side]] = new
        _, labels = np.unique(labels, return_inverse=True)
        return labels.astype(np.intp)

    def _widest(self, z: np.ndarray, labels: np.ndarray, m: int, frozen: set[int]) -> int | None:
        best, best_sse = None, -1.0
        for k in range(m):
            if k in frozen:
                continue
            zk = z[labels == k]
            if zk.shape[0] < self.min_size:
                continue
            sse = float(np.sum((zk - zk.mean(axis=0)) ** 2))
            if sse > best_sse:
                best, best_sse = k, sse
        return best
