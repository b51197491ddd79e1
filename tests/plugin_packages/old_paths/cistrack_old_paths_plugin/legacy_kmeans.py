"""A small k-means clusterer written against 0.1's paths (cistrack.component, cistrack.belief)."""
import numpy as np

from cistrack.belief import ParticleCloud  # noqa: F401  (imported as 0.1's docs showed)
from cistrack.component import check_int
from cistrack.hookspecs import hookimpl
from cistrack.interfaces import Clusterer


class LegacyKMeans(Clusterer):
    """Lloyd's k-means on standardised states, farthest-point initialisation.

    Parameters
    ----------
    n_components : int
        Number of clusters.
    n_iter : int
        Lloyd iterations.
    """

    def __init__(self, n_components: int = 2, n_iter: int = 20) -> None:
        self.n_components = check_int(self, "n_components", n_components, minimum=1)
        self.n_iter = check_int(self, "n_iter", n_iter, minimum=1)

    def cluster(self, x: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        z = (x - x.mean(axis=0)) / np.where(x.std(axis=0) > 0, x.std(axis=0), 1.0)
        k = min(self.n_components, len(z))
        centres = [z[rng.integers(len(z))]]
        for _ in range(1, k):
            d = np.min([((z - c) ** 2).sum(axis=1) for c in centres], axis=0)
            centres.append(z[int(np.argmax(d))])
        c = np.array(centres)
        labels = np.zeros(len(z), dtype=int)
        for _ in range(self.n_iter):
            labels = np.argmin(((z[:, None, :] - c[None]) ** 2).sum(axis=2), axis=1)
            c = np.array([z[labels == j].mean(axis=0) if np.any(labels == j) else c[j] for j in range(k)])
        return labels


@hookimpl
def cistrack_register(registry):
    registry.add("clustering", "legacy-kmeans", LegacyKMeans)
