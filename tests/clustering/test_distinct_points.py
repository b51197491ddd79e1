"""n_distinct_at_least: how many components a set of points can hold (distinct rows, up to k)."""
from __future__ import annotations

import numpy as np

from cistrack.plugins.clustering.points_and_labels import n_distinct_at_least


def test_points_all_different_give_k():
    x = np.random.default_rng(2).normal(size=(500, 6))
    assert n_distinct_at_least(x, 6) == 6


def test_rows_sharing_a_first_coordinate_still_count_as_distinct():
    x = np.zeros((100, 6))
    x[:, 3] = np.arange(100) % 4  # four distinct rows, all with the same first coordinate
    assert n_distinct_at_least(x, 6) == 4
    assert n_distinct_at_least(x, 3) == 3


def test_duplicates_count_once_and_rows_past_the_first_ones_are_seen():
    x = np.ones((1000, 6))
    x[900:, 0] = 2.0  # a second distinct row appears only after the first 64
    assert n_distinct_at_least(x, 6) == 2


def test_one_component_asked_for_is_one():
    assert n_distinct_at_least(np.zeros((10, 6)), 1) == 1
