"""k-means clustering of particles on standardised coordinates (numpy; scikit-learn's algorithm and results)."""
from __future__ import annotations

import warnings

import numpy as np

from cistrack.interfaces.component import check_choice, check_int
from cistrack.api import hookimpl
from cistrack.interfaces import Clusterer

from .lloyd import kmeans_fit, nearest_centres
from .thread_limits import limited_threads
from .points_and_labels import (Standardizer, check_points, compact_labels, n_distinct_at_least, sklearn_seed,
                                standardize)

__all__ = ["KMeansClusterer"]


class KMeansClusterer(Clusterer):
    """k-means (Lloyd) on standardised coordinates; the paper's clusterer for the PGM filter (and the default of cistrack's PGM, which updates each cluster with an iterated update).

    Parameters
    ----------
    n_components : int
        Number of clusters M (fewer when there are fewer distinct particles).
    n_init : int
        k-means++ restarts; 1 is enough for the filter's every-step use.
    max_iter : int
        Lloyd iterations per restart (clusters need not be converged to be useful components).
    n_threads : int
        OpenMP threads for the scikit-learn engine (0 = all cores); 1 avoids oversubscription
        when runs are parallelised across processes.
    max_fit_samples : int
        Lloyd iterations run on at most this many randomly chosen particles (drawn from the
        rng); every particle is then labelled by its nearest centroid. 0 fits on all particles.
        Centroids of a few clusters are estimated well from a few thousand points, and the
        PGM clusters at every update, so this is its largest saving (about 4x at N = 10,000).
    engine : str
        "numpy" (default): cistrack's numpy k-means (:mod:`.lloyd`), which returns scikit-learn's
        one-thread result bit for bit without importing scikit-learn (1.3 s of CPU) and without
        its per-call overhead; it hands a fit whose cluster empties to scikit-learn. "sklearn":
        scikit-learn's KMeans always (n_init > 1 also uses it).
    """

    def __init__(self, n_components: int = 6, n_init: int = 1, max_iter: int = 30, n_threads: int = 1,
                 max_fit_samples: int = 2500, engine: str = "numpy"):
        self.n_components = check_int(self, "n_components", n_components, minimum=1)
        self.n_init = check_int(self, "n_init", n_init, minimum=1)
        self.max_iter = check_int(self, "max_iter", max_iter, minimum=1)
        self.n_threads = check_int(self, "n_threads", n_threads, minimum=0)
        self.max_fit_samples = check_int(self, "max_fit_samples", max_fit_samples, minimum=0)
        self.engine = check_choice(self, "engine", engine, ("numpy", "sklearn"))

    def cluster(self, x: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Labels (N,) in [0, M) for particles ``x`` (N, d)."""
        x = check_points(x, self.registry_name or "kmeans")
        k = n_distinct_at_least(x, self.n_components)
        if k <= 1:
            return np.zeros(x.shape[0], dtype=np.intp)
        seed = sklearn_seed(rng)
        subsample = 0 < self.max_fit_samples < x.shape[0] and self.max_fit_samples >= 10 * k
        # subsampled: the fit's rows and then every row's label are standardised as needed, never
        # all N rows at once (at a million particles that copy was 48 MB)
        z = Standardizer(x) if subsample else standardize(x)
        fit = z.take(rng.choice(x.shape[0], size=self.max_fit_samples, replace=False)) if subsample else z
        found = None
        if self.engine == "numpy" and self.n_init == 1:
            found = kmeans_fit(fit, k, seed, max_iter=self.max_iter)
        if found is None:
            found = self._sklearn_fit(fit, k, seed)
        c, labels = found
        if subsample:
            labels = nearest_centres(z, c)
        return compact_labels(labels)

    def _sklearn_fit(self, fit: np.ndarray, k: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
        """scikit-learn's KMeans: centres (k, d) and labels (n,)."""
        from sklearn.cluster import KMeans  # on use: listing the registry must not load scikit-learn
        from sklearn.exceptions import ConvergenceWarning

        km = KMeans(n_clusters=k, n_init=self.n_init, max_iter=self.max_iter, random_state=seed)
        with warnings.catch_warnings(), limited_threads(self.n_threads):
            warnings.simplefilter("ignore", ConvergenceWarning)
            km.fit(fit)
        return km.cluster_centers_, km.labels_


@hookimpl
def cistrack_register(registry):
    registry.add("clustering", "kmeans", KMeansClusterer)
