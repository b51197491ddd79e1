"""cistrack's numpy k-means gives scikit-learn's one-thread KMeans result bit for bit (so the
filters' step tables do not change with the engine) without importing scikit-learn."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

from cistrack.plugins.clustering.kmeans import KMeansClusterer
from cistrack.plugins.clustering.lloyd import kmeans_fit, nearest_centres


def _cloud(seed: int, n: int, k: int) -> np.ndarray:
    """k anisotropic blobs in 6-D, one coordinate scaled by 1e3 and one by 1e-2."""
    g = np.random.default_rng(seed)
    centres = g.normal(size=(k, 6)) * 3.0
    x = centres[g.integers(k, size=n)] + g.normal(size=(n, 6)) * g.uniform(0.2, 3.0, size=6)
    return x * np.array([1e3, 1.0, 1e-2, 5.0, 1.0, 1.0])


def _sklearn(x, k, seed, max_iter):
    from sklearn.cluster import KMeans
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        km = KMeans(n_clusters=k, n_init=1, max_iter=max_iter, random_state=seed).fit(x)
    return km.cluster_centers_, km.labels_


@pytest.mark.parametrize("seed", range(12))
def test_centres_and_labels_equal_scikit_learns_bit_for_bit(seed):
    n, k = (300, 2500, 10_000)[seed % 3], 2 + seed % 7
    x = _cloud(seed, n, k)
    centres, labels = kmeans_fit(x, k, 1000 + seed, max_iter=30)
    want_c, want_l = _sklearn(x, k, 1000 + seed, 30)
    assert np.array_equal(centres, want_c)
    assert np.array_equal(labels, want_l)


def test_a_fit_stopped_by_the_iteration_limit_labels_by_the_final_centres():
    x = _cloud(3, 2000, 6)
    centres, labels = kmeans_fit(x, 6, 7, max_iter=2)
    want_c, want_l = _sklearn(x, 6, 7, 2)
    assert np.array_equal(centres, want_c) and np.array_equal(labels, want_l)
    d2 = ((x[:, None, :] - centres[None]) ** 2).sum(axis=2)
    assert np.array_equal(labels, np.argmin(d2, axis=1))


def test_a_cluster_that_empties_is_handed_back_as_none():
    # three distinct points, four clusters: a fourth centre coincides with one of the points and
    # loses every tie to the lower-numbered centre there, so its cluster is empty
    x = np.repeat(np.array([[0.0, 0.0], [10.0, 0.0], [0.0, 10.0]]), 4, axis=0)
    assert kmeans_fit(x, 4, 1) is None
    assert kmeans_fit(x, 3, 1) is not None


@pytest.mark.parametrize("n", [5000, 800])  # subsampled fit, and a fit on every particle
def test_the_numpy_engine_labels_as_the_sklearn_engine(n):
    x = _cloud(9, n, 5)
    a = KMeansClusterer(n_components=5).cluster(x, np.random.default_rng(4))
    b = KMeansClusterer(n_components=5, engine="sklearn").cluster(x, np.random.default_rng(4))
    assert np.array_equal(a, b)


def test_an_unknown_engine_is_refused_naming_the_choices():
    with pytest.raises(Exception, match="engine.*numpy.*sklearn"):
        KMeansClusterer(engine="fast")


@pytest.mark.parametrize("seed", range(4))
def test_nearest_centres_equals_numpys_argmin_of_the_expanded_distances(seed):
    g = np.random.default_rng(seed)
    z = g.normal(size=(5000, 6))
    c = g.normal(size=(2 + seed, 6))
    c[-1] = z[17]  # a centre on a point: distance rounding near zero
    want = np.argmin(np.einsum("ij,ij->i", z, z)[:, None] - 2.0 * z @ c.T + np.einsum("ij,ij->i", c, c)[None, :], axis=1)
    assert np.array_equal(nearest_centres(z, c), want)


def test_nearest_centres_breaks_ties_to_the_first_centre():
    z = np.array([[0.0, 0.0], [1.0, 0.0]])
    c = np.array([[0.5, 0.0], [0.5, 0.0], [-0.5, 0.0]])
    assert list(nearest_centres(z, c)) == [0, 0]
