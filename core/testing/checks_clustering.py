"""Conformance checks for Clusterer plugins (two well-separated blobs of particles)."""
from __future__ import annotations

import numpy as np

from cistrack.interfaces.clustering import Clusterer
from cistrack.units import state_to_km
from cistrack.testing.check_support import no_global_random_state, require, round_trip, unchanged
from cistrack.testing.fixtures import two_blobs

__all__ = ["CLUSTERING_CHECKS", "same_partition"]


def same_partition(a: np.ndarray, b: np.ndarray) -> float:
    """Fraction of particles whose label agrees after the best one-to-one relabelling of b."""
    agree = 0
    for la in np.unique(a):
        sel = a == la
        _, counts = np.unique(b[sel], return_counts=True)
        agree += counts.max()
    return agree / a.size


def _cluster(clusterer, x, seed=0) -> np.ndarray:
    labels = np.asarray(clusterer.cluster(x, np.random.default_rng(seed)))
    require(labels.shape == (x.shape[0],), f"cluster() returned shape {labels.shape}, expected (N,) = ({x.shape[0]},)")
    require(np.issubdtype(labels.dtype, np.integer), f"cluster() returned dtype {labels.dtype}, expected integers")
    m = int(labels.max()) + 1 if labels.size else 0
    require(labels.min() >= 0 and np.array_equal(np.unique(labels), np.arange(m)),
            f"labels must use every value in [0, M); got {np.unique(labels)}")
    return labels


def check_is_clusterer(c) -> None:
    require(isinstance(c, Clusterer), f"{type(c).__name__} does not derive from cistrack.interfaces.Clusterer")


def check_separates_two_blobs(c) -> None:
    """Two blobs 2,000 km apart (50 km spread) are never mixed within one cluster."""
    x, truth = two_blobs()
    labels = _cluster(c, x)
    require(labels.max() >= 1, "all particles of two blobs 2,000 km apart ended in one cluster")
    for k in range(labels.max() + 1):
        require(np.unique(truth[labels == k]).size == 1,
                f"cluster {k} mixes particles of two blobs 2,000 km apart")


def check_invariant_to_units(c) -> None:
    """The same particles in km and km/s give the same partition as in LU and VU (the
    clusterer standardises coordinates itself)."""
    x, _ = two_blobs()
    a = _cluster(c, x, seed=1)
    b = _cluster(c, state_to_km(x), seed=1)
    frac = same_partition(a, b)
    require(frac >= 0.99 and a.max() == b.max(),
            f"clustering the same particles in km instead of LU changed the partition ({100 * (1 - frac):.1f}% of "
            "particles, or the number of clusters): standardise the coordinates before clustering")


def check_reproducible(c) -> None:
    x, _ = two_blobs()
    with no_global_random_state("cluster()"), unchanged(x=x):
        a = _cluster(c, x, seed=4)
    b = _cluster(c, x, seed=4)
    require(np.array_equal(a, b), "cluster() with generators of the same seed gave different labels")


COUNT_LIMITS = ("n_components", "max_components")
"""Parameters that bound how many clusters a clusterer returns."""


def _with_limit(c, name: str, limit: int):
    """``c`` rebuilt with parameter ``name`` = ``limit``, or None when it does not take that value."""
    try:
        return type(c)(**{**c.get_params(), name: limit})
    except Exception:
        return None


def check_respects_n_components(c) -> None:
    """A clusterer given n_components = M (or max_components = M) returns at most M clusters, with
    its own value and with 2, on two blobs of 200 particles; one that chooses the count itself
    (``chooses_n_components = True``) is not held to its n_components."""
    get_params = getattr(c, "get_params", None)
    params = get_params() if callable(get_params) else {}
    hint = "n_components" if getattr(c, "chooses_n_components", False) else None
    names = [n for n in COUNT_LIMITS if n != hint and isinstance(params.get(n), int) and not isinstance(params.get(n), bool)]
    x, _ = two_blobs()
    for name in names:
        for limit, clusterer in ((params[name], c), (2, _with_limit(c, name, 2))):
            if clusterer is None:
                continue
            m = int(_cluster(clusterer, x).max()) + 1
            require(m <= limit, f"given {name}={limit}, cluster() returned {m} clusters of {x.shape[0]} particles: "
                                f"return at most {name} clusters (a clusterer that chooses the count itself, its "
                                f"{name} only a hint, says so with the class attribute chooses_n_components = True)")


def check_same_after_pickle(c) -> None:
    x, _ = two_blobs()
    other = round_trip(c)
    require(np.array_equal(_cluster(c, x, 2), _cluster(other, x, 2)), "the unpickled copy clusters differently")


CLUSTERING_CHECKS = [
    ("is_clusterer", check_is_clusterer),
    ("separates_two_blobs", check_separates_two_blobs),
    ("invariant_to_units", check_invariant_to_units),
    ("reproducible", check_reproducible),
    ("same_after_pickle", check_same_after_pickle),
    ("respects_n_components", check_respects_n_components),
]
