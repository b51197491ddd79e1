"""A clusterer that puts every particle in one component (a plain single-Gaussian PGM)."""
import numpy as np

from cistrack.plugin.hookspecs import hookimpl
from cistrack.interfaces import Clusterer


class OneCluster(Clusterer):
    """Every particle in one component: the PGM filter then reduces to an EnKF."""

    def __init__(self) -> None:
        pass

    def cluster(self, x: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        return np.zeros(np.asarray(x).shape[0], dtype=int)


@hookimpl
def cistrack_register(registry):
    registry.add("clustering", "one-cluster", OneCluster)
