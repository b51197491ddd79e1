"""The memory-lean forms of mixture sampling, group moments and nearest-centre labelling give the
same numbers, bit for bit, as the plain formulas (one normal draw for all points, a copy of each
group's rows, one product for all points)."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.model.belief import GaussianMixture
from cistrack.plugins.filters.kalman_update import group_moments


def _mixture(seed: int, m: int) -> GaussianMixture:
    r = np.random.default_rng(seed)
    w = r.random(m) ** 3
    a = r.normal(size=(m, 6, 6)) * 10.0 ** r.uniform(-6, 2, size=(m, 1, 1))
    return GaussianMixture(w / w.sum(), r.normal(size=(m, 6)) * 100.0,
                           a @ np.transpose(a, (0, 2, 1)) + 1e-12 * np.eye(6))


def _plain_sample(mix: GaussianMixture, n: int, rng):
    labels = rng.choice(mix.n_components, size=n, p=mix.weights)
    labels.sort()
    z = rng.standard_normal((n, mix.dim))
    out = np.empty((n, mix.dim))
    for i in range(mix.n_components):
        sel = labels == i
        out[sel] = mix.means[i] + z[sel] @ mix.cholesky()[i].T
    return out, labels


@pytest.mark.parametrize("n,m", [(1, 1), (7, 3), (5_000, 9), (200_000, 2)])
def test_mixture_samples_equal_one_draw_for_all_points(n, m):
    mix = _mixture(n + m, m)
    ra, rb = np.random.default_rng(4), np.random.default_rng(4)
    got, want = mix.sample(n, ra), _plain_sample(mix, n, rb)
    assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1])
    assert ra.random() == rb.random()  # and the generator is left in the same state


@pytest.mark.parametrize("with_d", [True, False])
def test_group_moments_equal_the_per_group_formulas(with_d):
    r = np.random.default_rng(8)
    x = r.normal(size=(30_000, 6)) * np.logspace(-5, 3, 6)
    d = r.normal(size=(30_000, 2)) * 1e-4 if with_d else None
    labels = r.integers(0, 7, size=30_000)
    mom = group_moments(x, d, labels, 8)  # group 7 is empty
    y = x if d is None else np.hstack([x, d])
    for i in range(7):
        yi = y[labels == i]
        mean = yi.mean(axis=0)
        c = yi - mean
        cov = (c.T @ c) / (yi.shape[0] - 1)  # c.T @ c of one array: numpy's symmetric product
        assert np.array_equal(mom.mean_x[i], mean[:6]) and np.array_equal(mom.pxx[i], cov[:6, :6])
        if with_d:
            assert np.array_equal(mom.mean_d[i], mean[6:]) and np.array_equal(mom.pxd[i], cov[:6, 6:])
    assert mom.counts[7] == 0 and not mom.pxx[7].any()


def test_group_moments_of_groups_of_one_two_and_three_equal_the_formulas():
    r = np.random.default_rng(21)
    x = r.normal(size=(6, 6)) * 1e3
    labels = np.array([2, 0, 2, 3, 2, 0])  # groups of 2, none, 3 and 1 particles
    mom = group_moments(x, None, labels, 4)
    for i, n in enumerate([2, 0, 3, 1]):
        assert mom.counts[i] == n
        if n == 0:
            assert not mom.mean_x[i].any() and not mom.pxx[i].any()
            continue
        xi = x[labels == i]
        assert np.array_equal(mom.mean_x[i], xi.mean(axis=0))
        c = xi - xi.mean(axis=0)
        assert np.array_equal(mom.pxx[i], (c.T @ c) / (n - 1) if n > 1 else np.zeros((6, 6)))


def test_nearest_centres_in_blocks_equal_the_one_product_formula():
    from cistrack.plugins.clustering.lloyd import _ROWS_AT_ONCE, nearest_centres

    r = np.random.default_rng(3)
    z = np.round(r.normal(size=(2 * _ROWS_AT_ONCE + 5, 6)), 1)  # rounded: ties occur
    c = np.round(r.normal(size=(9, 6)), 1)
    plain = np.argmin(np.einsum("ij,ij->i", z, z)[:, None] - (2.0 * z) @ c.T + np.einsum("ij,ij->i", c, c), axis=1)
    assert np.array_equal(nearest_centres(z, c), plain)


def test_group_moments_in_blocks_keep_the_mean_and_the_covariance(monkeypatch):
    """A group larger than GROUP_BLOCK_ROWS: the same mean bits, the covariance to rounding."""
    from cistrack.plugins.filters import kalman_update

    r = np.random.default_rng(8)
    x, d = r.normal(size=(5000, 6)) * 1e3 + 7.0, r.normal(size=(5000, 2))
    labels = r.integers(0, 3, size=5000)
    whole = group_moments(x, d, labels, 3)
    monkeypatch.setattr(kalman_update, "GROUP_BLOCK_ROWS", 500)  # every group in 3-4 blocks
    blocks = group_moments(x, d, labels, 3)
    assert np.array_equal(blocks.mean_x, whole.mean_x) and np.array_equal(blocks.mean_d, whole.mean_d)
    for a, b in ((blocks.pxx, whole.pxx), (blocks.pxd, whole.pxd), (blocks.pdd, whole.pdd)):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12 * np.abs(b).max())
    np.testing.assert_allclose(blocks.pxx[1], np.cov(x[labels == 1].T), rtol=1e-12)
