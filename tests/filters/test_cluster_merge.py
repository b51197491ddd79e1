"""Merging clusters too small for a covariance: each goes to the nearest large one, the labels
are renumbered without gaps, and a large cloud is summed in blocks with the same outcome."""
from __future__ import annotations

import numpy as np

import cistrack.plugins.filters.pgm.cluster_merge as cluster_merge
from cistrack.plugins.filters.pgm.cluster_merge import merge_small_clusters, merged_cluster_targets


def _cloud(n: int, seed: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """Three well-separated large clusters (labels 0, 2, 4) and two small ones beside 2 and 4."""
    rng = np.random.default_rng(seed)
    centres = {0: 0.0, 2: 10.0, 4: -10.0, 1: 9.0, 3: -9.5}
    sizes = {0: n // 3, 2: n // 3, 4: n - 2 * (n // 3) - 20, 1: 12, 3: 8}
    labels = np.concatenate([np.full(sizes[k], k) for k in centres])
    x = np.vstack([rng.standard_normal((sizes[k], 6)) * [1, 2, 3, 0.5, 0.2, 1] + centres[k] for k in centres])
    perm = rng.permutation(labels.size)
    return x[perm], labels[perm]


def test_each_small_cluster_joins_the_nearest_large_one_and_labels_have_no_gaps():
    x, labels = _cloud(3000)
    new, merged = merge_small_clusters(x, labels, 100)
    assert merged == 2
    assert sorted(set(new.tolist())) == [0, 1, 2]
    assert np.all(new[labels == 1] == new[labels == 2][0])
    assert np.all(new[labels == 3] == new[labels == 4][0])


def test_the_targets_relabel_in_place_as_the_merge_does():
    x, labels = _cloud(3000)
    target, merged = merged_cluster_targets(x, labels, 100)
    own = labels.astype(np.intp)
    np.take(target, own, out=own, mode="clip")
    assert np.array_equal(own, merge_small_clusters(x, labels, 100)[0]) and merged == 2


def test_nothing_small_leaves_the_labels_as_they_are():
    x, labels = _cloud(3000)
    assert merged_cluster_targets(x, labels, 5) == (None, 0)
    assert np.array_equal(merge_small_clusters(x, labels, 5)[0], labels)


def test_a_cloud_summed_in_blocks_merges_as_one_summed_whole(monkeypatch):
    x, labels = _cloud(5000)
    whole = merge_small_clusters(x, labels, 100)
    monkeypatch.setattr(cluster_merge, "MERGE_WHOLE_ROWS", 700)
    blocked = merge_small_clusters(x, labels, 100)
    assert np.array_equal(whole[0], blocked[0]) and whole[1] == blocked[1]
    assert np.allclose(cluster_merge._scaled_means(x, labels, np.bincount(labels)),
                       _whole_scaled_means(x, labels), rtol=1e-12, atol=1e-12)


def _whole_scaled_means(x: np.ndarray, labels: np.ndarray) -> np.ndarray:
    z = x / x.std(axis=0)
    return np.stack([z[labels == k].mean(axis=0) for k in range(labels.max() + 1)])
