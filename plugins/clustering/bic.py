"""Clustering that chooses its own number of components by the Bayesian information criterion."""
from __future__ import annotations

import numpy as np

from cistrack.interfaces.component import check_int, check_positive
from cistrack.api import hookimpl
from cistrack.interfaces import Clusterer

from .gmm import fit_gmm_labels
from .points_and_labels import check_points, compact_labels, n_distinct_at_least, standardize

__all__ = ["BICClusterer"]


class BICClusterer(Clusterer):
    """Gaussian mixtures with 1..max_components components on standardised coordinates; the
    one with the lowest BIC labels the particles.

    Parameters
    ----------
    max_components : int
        Largest number of components tried.
    max_iter : int
        EM iterations per fit.
    reg_covar : float
        Diagonal regularisation of each standardised covariance.
    max_fit_samples : int
        Each fit (and its BIC) uses a random subset of at most this many particles.
    n_threads : int
        OpenMP threads for scikit-learn's k-means initialisation (0 = all cores).
    """

    def __init__(self, max_components: int = 8, max_iter: int = 100, reg_covar: float = 1e-6,
                 max_fit_samples: int = 3000, n_threads: int = 1):
        self.max_components = check_int(self, "max_components", max_components, minimum=1)
        self.max_iter = check_int(self, "max_iter", max_iter, minimum=1)
        self.reg_covar = check_positive(self, "reg_covar", reg_covar)
        self.max_fit_samples = check_int(self, "max_fit_samples", max_fit_samples, minimum=2)
        self.n_threads = check_int(self, "n_threads", n_threads, minimum=0)
        self.last_n_components: int | None = None

    def cluster(self, x: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Labels (N,) in [0, M) for particles ``x`` (N, d), M chosen by BIC."""
        x = check_points(x, self.registry_name or "bic")
        d = x.shape[1]
        # a full-covariance component needs more than d points to be estimable
        k_max = min(self.max_components, max(1, x.shape[0] // (d + 1)))
        k_max = n_distinct_at_least(x, k_max)
        z = standardize(x)
        best_labels = np.zeros(x.shape[0], dtype=np.intp)
        best_bic = np.inf
        for k in range(1, k_max + 1):
            labels, bic = fit_gmm_labels(z, k, rng, self.max_iter, self.reg_covar, self.max_fit_samples,
                                        self.n_threads)
            if bic < best_bic:
                best_bic, best_labels = bic, labels
        labels = compact_labels(best_labels)
        self.last_n_components = int(labels.max()) + 1
        return labels


@hookimpl
def cistrack_register(registry):
    registry.add("clustering", "bic", BICClusterer)
