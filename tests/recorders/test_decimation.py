"""The recorder's decimation: a capped, seeded subsample of the particles that keeps every mixture
component, and the heaviest components' ellipsoids."""
from __future__ import annotations

import numpy as np

from cistrack.plugins.recorders.decimation import (MIN_SHARE, component_quotas, heaviest_components,
                                                    subsample_indices)
from cistrack.plugins.recorders.rerun_recorder import RerunRecorder


def labels_of(counts: list[int], seed: int = 5) -> np.ndarray:
    """Component labels of ``sum(counts)`` particles in a shuffled order."""
    lab = np.repeat(np.arange(len(counts)), counts)
    return np.random.default_rng(seed).permutation(lab)


def test_nothing_is_dropped_from_a_cloud_within_the_cap():
    assert subsample_indices(100, 100) is None
    assert subsample_indices(100, 500, labels=np.zeros(100)) is None


def test_the_subsample_has_max_points_distinct_sorted_rows():
    keep = subsample_indices(10_000, 2_000, seed=3, labels=labels_of([9_000, 990, 10]))
    assert keep.shape == (2_000,)
    assert np.all(np.diff(keep) > 0) and keep[0] >= 0 and keep[-1] < 10_000


def test_a_light_component_keeps_its_share_of_the_logged_particles():
    lab = labels_of([9_950, 40, 10])
    kept = lab[subsample_indices(lab.size, 2_000, labels=lab)]
    counts = np.bincount(kept, minlength=3)
    assert counts[1] == 40 and counts[2] == 10  # fewer than 2 % of 2,000: all of them
    assert counts.sum() == 2_000


def test_a_plain_draw_would_lose_a_light_component():
    """What the per-component quota prevents: 5 of 10,000 particles seldom survive a 1-in-50 draw."""
    lab = labels_of([9_995, 5])
    plain = lab[subsample_indices(lab.size, 200, seed=1)]
    kept = lab[subsample_indices(lab.size, 200, seed=1, labels=lab)]
    assert 1 not in plain
    assert np.count_nonzero(kept == 1) == 4  # 2 % of 200


def test_the_subsample_is_the_same_for_the_same_seed_and_labels_and_differs_by_seed():
    lab = labels_of([5_000, 3_000, 2_000])
    a = subsample_indices(lab.size, 1_000, seed=7, labels=lab)
    np.testing.assert_array_equal(a, subsample_indices(lab.size, 1_000, seed=7, labels=lab.copy()))
    assert not np.array_equal(a, subsample_indices(lab.size, 1_000, seed=8, labels=lab))


def test_quotas_are_proportional_above_the_minimum_share():
    q = component_quotas(np.array([6_000, 3_000, 1_000]), 1_000)
    assert q.sum() == 1_000
    np.testing.assert_allclose(q, [600, 300, 100], atol=2)
    assert MIN_SHARE * 1_000 <= q.min()


def test_quotas_with_more_components_than_points_give_one_to_the_largest():
    np.testing.assert_array_equal(component_quotas(np.array([3, 9, 1, 5]), 2), [0, 1, 0, 1])


def test_heaviest_components_are_the_largest_weights_in_index_order():
    np.testing.assert_array_equal(heaviest_components([0.1, 0.4, 0.05, 0.3, 0.15], 3), [1, 3, 4])
    np.testing.assert_array_equal(heaviest_components([0.5, 0.5], 4), [0, 1])
    assert heaviest_components([0.5, 0.5], 0).size == 0


def test_a_recorder_logs_at_most_2000_particles_and_4_ellipsoids_by_default(tmp_path):
    rec = RerunRecorder(path=str(tmp_path / "a.rrd"))
    assert (rec.max_points, rec.max_ellipsoids) == (2_000, 4)
