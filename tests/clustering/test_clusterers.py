"""Clusterers: labels cover 0..M-1, separated blobs are found, degenerate input is handled,
results depend only on the Generator."""
from __future__ import annotations

import pickle

import numpy as np
import pytest

from cistrack.errors import ParameterError
from cistrack.interfaces import Clusterer
from cistrack.plugin.registry import load_registry

NAMES = ["kmeans", "gmm", "bic"]


@pytest.fixture(scope="module")
def registry():
    return load_registry()


def blobs(rng, centres, n=400, scale=None):
    """Blobs in 6-D at ``centres`` (k, 6); coordinates scaled by ``scale`` (6,) like LU vs VU."""
    x = np.vstack([c + 0.1 * rng.standard_normal((n, 6)) for c in centres])
    return x * (np.ones(6) if scale is None else scale), np.repeat(np.arange(len(centres)), n)


def same_partition(a, b):
    """Labels equal up to renaming."""
    pairs = set(zip(a.tolist(), b.tolist()))
    return len(pairs) == len(set(a.tolist())) == len(set(b.tolist()))


@pytest.mark.parametrize("name", NAMES)
def test_registered_as_a_clusterer(registry, name):
    assert isinstance(registry.create("clustering", name), Clusterer)


@pytest.mark.parametrize("name", ["kmeans", "gmm"])
def test_separated_blobs_are_recovered_on_very_different_coordinate_scales(registry, name):
    rng = np.random.default_rng(0)
    centres = np.eye(6)[:3] * 3.0
    # positions ~1e-3 LU and velocities ~1e-6 VU: standardisation must make both count
    x, truth = blobs(rng, centres, scale=np.array([1e-3, 1e-3, 1e-3, 1e-6, 1e-6, 1e-6]))
    labels = registry.create("clustering", name, n_components=3).cluster(x, np.random.default_rng(1))
    assert same_partition(labels, truth)


def test_bic_chooses_the_number_of_blobs(registry):
    rng = np.random.default_rng(0)
    centres = np.eye(6)[:4] * 3.0
    x, truth = blobs(rng, centres)
    labels = registry.create("clustering", "bic", max_components=7).cluster(x, np.random.default_rng(1))
    assert labels.max() + 1 == 4
    assert same_partition(labels, truth)


@pytest.mark.parametrize("name", NAMES)
def test_fewer_points_than_components_gives_valid_labels(registry, name):
    x = np.random.default_rng(0).standard_normal((3, 6))
    params = {"max_components": 8} if name == "bic" else {"n_components": 8}
    labels = registry.create("clustering", name, **params).cluster(x, np.random.default_rng(0))
    assert labels.shape == (3,)
    assert set(labels.tolist()) == set(range(labels.max() + 1))


@pytest.mark.parametrize("name", NAMES)
def test_duplicate_points_give_valid_labels(registry, name):
    x = np.repeat(np.random.default_rng(0).standard_normal((2, 6)), 50, axis=0)
    labels = registry.create("clustering", name).cluster(x, np.random.default_rng(0))
    assert labels.shape == (100,)
    assert set(labels.tolist()) == set(range(labels.max() + 1))
    assert labels.max() + 1 <= 2


@pytest.mark.parametrize("name", NAMES)
def test_same_generator_seed_gives_same_labels(registry, name):
    x = np.random.default_rng(0).standard_normal((600, 6))
    c = registry.create("clustering", name)
    a = c.cluster(x, np.random.default_rng(3))
    b = pickle.loads(pickle.dumps(c)).cluster(x, np.random.default_rng(3))
    np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("name", NAMES)
def test_nan_points_are_a_clear_error(registry, name):
    x = np.zeros((10, 6))
    x[3, 2] = np.nan
    with pytest.raises(ParameterError, match="NaN"):
        registry.create("clustering", name).cluster(x, np.random.default_rng(0))


def test_invalid_parameter_names_the_clusterer_and_value(registry):
    with pytest.raises(ParameterError, match="n_components"):
        registry.create("clustering", "kmeans", n_components=0)
