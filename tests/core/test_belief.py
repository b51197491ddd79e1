"""Gaussian mixtures and particle clouds against closed forms and scipy."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import multivariate_normal

from cistrack.model.belief import Belief, GaussianMixture, ParticleCloud, regularize_covariance
from cistrack.evaluation.metrics import LOG_JACOBIAN_KM, entropy, step_metrics


def _spd(rng, d):
    a = rng.standard_normal((d, d))
    return a @ a.T + d * np.eye(d)


def test_mixture_logpdf_equals_weighted_sum_of_scipy_densities(rng):
    means = rng.standard_normal((3, 6))
    covs = np.stack([_spd(rng, 6) for _ in range(3)])
    w = np.array([0.2, 0.5, 0.3])
    gm = GaussianMixture(w, means, covs)
    x = rng.standard_normal((50, 6)) * 2
    ref = np.log(sum(w[i] * multivariate_normal(means[i], covs[i]).pdf(x) for i in range(3)))
    np.testing.assert_allclose(gm.logpdf(x), ref, rtol=1e-10)


def test_mixture_logpdf_stays_finite_far_in_the_tails():
    gm = GaussianMixture([0.5, 0.5], [[0.0], [1.0]], [[[1e-6]], [[1e-6]]])
    lp = gm.logpdf(np.array([[100.0]]))
    assert np.isfinite(lp).all() and lp[0] < -1e9


def test_mixture_moments_follow_the_law_of_total_covariance(rng):
    gm = GaussianMixture([0.3, 0.7], [[0.0, 0.0], [2.0, 1.0]], [np.eye(2), 2 * np.eye(2)])
    x, labels = gm.sample(200_000, rng)
    np.testing.assert_allclose(x.mean(axis=0), gm.mean, atol=0.02)
    np.testing.assert_allclose(np.cov(x.T), gm.covariance, atol=0.03)
    assert abs(np.mean(labels == 0) - 0.3) < 0.01


def test_sampling_is_reproducible_for_a_seed():
    gm = GaussianMixture([0.5, 0.5], [[0.0], [3.0]], [[[1.0]], [[1.0]]])
    a, _ = gm.sample(10, np.random.default_rng(7))
    b, _ = gm.sample(10, np.random.default_rng(7))
    np.testing.assert_array_equal(a, b)


def test_inconsistent_mixture_shapes_are_rejected():
    with pytest.raises(ValueError, match="inconsistent mixture shapes"):
        GaussianMixture([1.0], [[0.0, 0.0]], np.eye(3)[None])


def test_particle_cloud_moment_match_has_the_sample_mean_and_covariance(rng):
    x = rng.standard_normal((1000, 6))
    cloud = ParticleCloud(x, epoch=0.0)
    mm = cloud.moment_match()
    np.testing.assert_allclose(mm.means[0], x.mean(axis=0))
    np.testing.assert_allclose(mm.covariances[0], np.cov(x.T))


def test_entropy_estimate_of_a_gaussian_matches_the_closed_form(rng):
    cov = _spd(rng, 6) * 1e-8
    gm = GaussianMixture([1.0], np.zeros((1, 6)), cov[None])
    x, _ = gm.sample(100_000, rng)
    h = entropy(Belief(0.0, gm, ParticleCloud(x, 0.0)))
    closed = 0.5 * np.log(np.linalg.det(2 * np.pi * np.e * cov)) + LOG_JACOBIAN_KM
    assert abs(h - closed) < 0.02


def test_a_sample_of_weight_zero_where_the_density_is_zero_adds_nothing_to_the_entropy(rng):
    """0 x log 0 is 0 in the weighted sum, not NaN (a particle filter whose weights collapsed)."""
    gm = GaussianMixture([1.0], np.zeros((1, 6)), (np.eye(6) * 1e-8)[None])
    x, _ = gm.sample(3, rng)
    w = np.array([0.5, 0.5, 0.0])
    lp = gm.logpdf(x)
    lp[2] = -np.inf
    h = entropy(Belief(0.0, gm, ParticleCloud(x, 0.0, weights=w)), sample_logpdf=lp)
    assert h == pytest.approx(-(0.5 * lp[0] + 0.5 * lp[1]) + LOG_JACOBIAN_KM, rel=1e-12)


def test_nees_of_the_mean_is_chi_square_with_six_degrees_of_freedom(rng):
    cov = np.diag([1e-6] * 3 + [1e-8] * 3)
    gm = GaussianMixture([1.0], np.zeros((1, 6)), cov[None])
    x, _ = gm.sample(2000, rng)
    bel = Belief(0.0, gm, ParticleCloud(x, 0.0))
    truths, _ = gm.sample(400, rng)
    nees = [step_metrics(bel, t)["nees"] for t in truths]
    assert abs(np.mean(nees) - 6.0) < 0.5
    hdr = [step_metrics(bel, t)["hdr_level"] for t in truths[:200]]
    assert abs(np.mean(hdr) - 0.5) < 0.06  # truth's HDR level is uniform for a consistent belief


def _per_point_logpdf(x, means, linv, const, logw):
    """The density table by a plain loop over points and components, in Python floats (the same
    IEEE double operations in the same order as the compiled kernel promises)."""
    out = np.empty((x.shape[0], means.shape[0]))
    d = x.shape[1]
    for n in range(x.shape[0]):
        for m in range(means.shape[0]):
            diff = [float(x[n, b]) - float(means[m, b]) for b in range(d)]
            maha = 0.0
            for a in range(d):
                s = 0.0
                for b in range(a + 1):
                    s += float(linv[m, a, b]) * diff[b]
                maha += s * s
            out[n, m] = float(const[m]) + float(logw[m]) - 0.5 * maha
    return out


@pytest.mark.parametrize("d", [3, 6, 7])  # 6: the state's own kernel (registers); others the general one
@pytest.mark.parametrize("n", [1, 255, 256, 300, 513])  # around the kernel's block of 256 points
def test_blocked_density_kernel_equals_a_per_point_loop_bit_for_bit(n, d):
    from cistrack.model.mixture_density import whitened_kernel

    g = np.random.default_rng(n)
    m = 3
    x, means = g.normal(size=(n, d)), g.normal(size=(m, d))
    linv = np.ascontiguousarray(np.tril(g.normal(size=(m, d, d))))
    const, logw = g.normal(size=m), g.normal(size=m)
    out = np.empty((n, m))
    whitened_kernel(d)(0, n, x, means, linv, const, logw, out)
    assert np.array_equal(out, _per_point_logpdf(x, means, linv, const, logw))


def test_the_general_density_kernel_gives_the_six_dimensional_kernels_numbers():
    from cistrack.model.mixture_density import _whitened_logpdf, whitened_kernel

    g = np.random.default_rng(12)
    n, m = 700, 5
    x, means = g.normal(size=(n, 6)) * 3.0, g.normal(size=(m, 6))
    linv = np.ascontiguousarray(np.tril(g.normal(size=(m, 6, 6))))
    const, logw = g.normal(size=m), g.normal(size=m)
    a, b = np.empty((n, m)), np.empty((n, m))
    _whitened_logpdf(0, n, x, means, linv, const, logw, a)
    whitened_kernel(6)(0, n, x, means, linv, const, logw, b)
    assert whitened_kernel(6) is not _whitened_logpdf and np.array_equal(a, b)


def _plain_logsumexp(row):
    """log sum exp by the textbook loop in Python floats: the max, then exp of every difference."""
    if any(v != v for v in row):
        return float("nan")
    mx = max(row)
    if not np.isfinite(mx):
        mx = 0.0
    s = 0.0
    for v in row:
        s += float(np.exp(v - mx))
    return mx + float(np.log(s)) if s > 0 else -np.inf


def test_row_logsumexp_equals_the_textbook_loop_bit_for_bit_with_ties_underflow_and_infinities():
    from cistrack.model.mixture_density import _row_logsumexp

    g = np.random.default_rng(13)
    rows = [g.normal(size=6) * 5.0 for _ in range(200)]
    rows += [np.array([1.5, 1.5, 0.2, 1.5, -3.0, 0.0]),            # the maximum three times
             np.array([0.0, -745.0, -745.2, -749.9, -750.0, -1e4]),  # terms that underflow to 0 or not
             np.array([-np.inf] * 6), np.array([-np.inf, 2.0, -np.inf, 1.0, -np.inf, 0.5]),
             np.array([np.inf, 1.0, 0.0, -1.0, 2.0, 3.0]), np.array([1.0, np.nan, 0.0, 0.0, 0.0, 0.0]),
             np.array([-0.0, 0.0, -1e-300, 1e-300, -5e-324, 5e-324])]
    a = np.array(rows)
    got = np.empty(a.shape[0])
    with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
        _row_logsumexp(0, a.shape[0], a, got)
        want = np.array([_plain_logsumexp([float(v) for v in r]) for r in rows])
    assert np.array_equal(got, want, equal_nan=True)


@pytest.mark.parametrize("threads", ["1", "2", "3"])
def test_mixture_density_of_many_points_is_the_same_on_any_number_of_threads(monkeypatch, threads):
    from cistrack.model.belief import GaussianMixture
    from cistrack.model.mixture_density import _THREADED_ROWS

    g = np.random.default_rng(11)
    m, n = 4, _THREADED_ROWS + 1001
    a = g.normal(size=(m, 6, 6))
    mix = GaussianMixture(np.full(m, 0.25), g.normal(size=(m, 6)), a @ a.transpose(0, 2, 1) + np.eye(6))
    x = g.normal(size=(n, 6)) * 2.0
    monkeypatch.setenv("CISTRACK_NUM_THREADS", threads)
    got = mix.logpdf(x)
    table = np.empty((n, m))
    linv, const = mix._whitening()
    from cistrack.model.belief import _row_logsumexp, _whitened_logpdf

    _whitened_logpdf(0, n, x, mix.means, linv, const, np.log(mix.weights), table)
    want = np.empty(n)
    _row_logsumexp(0, n, table, want)  # one thread, one range
    assert np.array_equal(got, want)


def test_position_marginal_of_a_mixture_has_the_position_blocks_and_the_closed_form_density():
    rng = np.random.default_rng(7)
    a = rng.normal(size=(2, 6, 6))
    covs = np.einsum("kij,klj->kil", a, a) + 0.1 * np.eye(6)
    gm = GaussianMixture(np.array([0.3, 0.7]), rng.normal(size=(2, 6)), covs)
    pos = gm.marginal(slice(0, 3))
    x = rng.normal(size=(5, 3))
    expected = np.log(sum(w * multivariate_normal(m[:3], c[:3, :3]).pdf(x)
                          for w, m, c in zip(gm.weights, gm.means, gm.covariances)))
    np.testing.assert_allclose(pos.logpdf(x), expected, rtol=1e-12)


def test_a_stack_regularized_each_on_its_own_changes_only_the_matrix_that_needs_it():
    good = np.array([[2.0, 0.3], [0.3, 1.0]])
    flat = np.array([[1.0, 1.0], [1.0, 1.0]])  # singular: an eigenvalue below the floor
    out = regularize_covariance(np.stack([good, flat]), 1e-9, each=True)
    assert np.array_equal(out[0], regularize_covariance(good, 1e-9))
    assert np.array_equal(out[1], regularize_covariance(flat, 1e-9))
    assert np.linalg.eigvalsh(out[1]).min() >= 1e-9 * 0.999


def test_the_nees_of_a_collapsed_belief_is_infinite_without_a_warning():
    import warnings

    from cistrack.evaluation.metrics import nees

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert nees(np.full(6, 1e10), np.eye(6) * 1e-300) == np.inf
