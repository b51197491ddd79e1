"""The clusterers' shared helpers give numpy's results bit for bit (the filters' step tables do
not depend on which implementation ran)."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.plugins.clustering.points_and_labels import compact_labels, standardize


def _numpy_standardize(x: np.ndarray) -> np.ndarray:
    mean = x.mean(axis=0)
    std = x.std(axis=0)
    std[~(std > 0)] = 1.0
    return (x - mean) / std


@pytest.mark.parametrize("n", [1, 2, 7, 2500, 10_000, 30_001])
def test_standardize_equals_numpys_mean_and_std_bit_for_bit(n):
    g = np.random.default_rng(n)
    x = g.normal(size=(n, 6)) * g.uniform(1e-3, 1e4, size=6) + g.normal(size=6) * 1e3
    assert np.array_equal(standardize(x), _numpy_standardize(x))


def test_standardize_only_shifts_a_coordinate_without_spread():
    x = np.column_stack([np.full(50, 3.0), np.arange(50.0)])
    z = standardize(x)
    assert np.array_equal(z[:, 0], np.zeros(50))
    assert np.array_equal(z, _numpy_standardize(x))


def test_standardize_accepts_a_non_contiguous_view():
    x = np.random.default_rng(1).normal(size=(6, 400)).T
    assert not x.flags.c_contiguous
    assert np.array_equal(standardize(x), _numpy_standardize(x))


@pytest.mark.parametrize("labels", [[0, 0, 1], [5, 2, 5, 9, 2], [3], [1, 0, 4, 4, 0]])
def test_compact_labels_equals_the_inverse_of_numpys_unique(labels):
    got = compact_labels(np.array(labels))
    assert got.dtype == np.intp
    assert np.array_equal(got, np.unique(labels, return_inverse=True)[1])


def test_compact_labels_of_negative_labels_still_ranks_them():
    assert np.array_equal(compact_labels(np.array([-2, 7, -2, 3])), [0, 2, 0, 1])
