"""The numba EM engine of the gmm clusterer: the same statistical algorithm as scikit-learn's
full-covariance GaussianMixture (checked against a hand-written numpy EM step, scikit-learn's
fit, and the generating parameters of a synthetic mixture)."""
from __future__ import annotations

import numpy as np
import pytest
from sklearn.mixture import GaussianMixture

from cistrack.errors import ParameterError
from cistrack.plugins.clustering.em_numba import em_fit, em_iteration, m_step, one_hot, predict_labels
from cistrack.plugins.clustering.kmeans_numba import kmeans_labels
from cistrack.plugins.clustering.gmm import GMMClusterer

D = 6
WEIGHTS = np.array([0.5, 0.3, 0.2])


def _random_cov(rng, scale):
    a = rng.standard_normal((D, D))
    return scale * (a @ a.T / D + 0.5 * np.eye(D))


@pytest.fixture(scope="module")
def mixture():
    """A well-separated 3-component 6-D mixture: (points (n, 6), labels, weights, means, covs)."""
    rng = np.random.default_rng(11)
    n = 6000
    means = np.array([np.zeros(D), np.r_[8.0, np.zeros(D - 1)], np.r_[0.0, 8.0, np.zeros(D - 2)]])
    covs = np.array([_random_cov(rng, s) for s in (1.0, 0.5, 0.8)])
    labels = rng.choice(3, size=n, p=WEIGHTS)
    x = np.empty((n, D))
    for c in range(3):
        idx = labels == c
        x[idx] = rng.multivariate_normal(means[c], covs[c], size=idx.sum())
    return x, labels, WEIGHTS, means, covs


def _matched(true_labels, labels, k):
    """Permutation perm with perm[fitted label] = true label (majority vote)."""
    return np.array([np.bincount(true_labels[labels == j], minlength=k).argmax() for j in range(k)])


def _agreement(a, b, k):
    perm = _matched(a, b, k)
    return np.mean(perm[b] == a)


def _fit_numba(x, k, seed):
    resp0 = one_hot(kmeans_labels(x, k, np.random.default_rng(seed)), k)
    fit = em_fit(x, resp0, reg_covar=1e-6, tol=1e-3, max_iter=100)
    return fit["weights"], fit["means"], fit["covariances"], predict_labels(x, fit)


def _fit_sklearn(x, k, seed):
    gm = GaussianMixture(k, covariance_type="full", tol=1e-3, max_iter=100, reg_covar=1e-6,
                         init_params="kmeans", random_state=seed).fit(x)
    return gm.weights_, gm.means_, gm.covariances_, gm.predict(x)


@pytest.mark.parametrize("engine", [_fit_numba, _fit_sklearn], ids=["numba", "sklearn"])
def test_fit_recovers_generating_parameters_within_sampling_error(mixture, engine):
    x, labels, weights, means, covs = mixture
    n = x.shape[0]
    w_fit, mu_fit, cov_fit, found = engine(x, 3, 3)
    perm = _matched(labels, found, 3)
    assert sorted(perm) == [0, 1, 2]
    for j, c in enumerate(perm):
        nk = weights[c] * n
        assert abs(w_fit[j] - weights[c]) < 5 * np.sqrt(weights[c] * (1 - weights[c]) / n)
        se_mean = np.sqrt(np.diag(covs[c]) / nk)
        assert np.all(np.abs(mu_fit[j] - means[c]) < 5 * se_mean)
        sd = np.sqrt(np.diag(covs[c]))
        se_cov = np.sqrt((np.outer(sd, sd) ** 2 + covs[c] ** 2) / nk)
        assert np.all(np.abs(cov_fit[j] - covs[c]) < 5 * se_cov)


def test_engines_agree_on_labels_of_a_separated_mixture(mixture):
    x, labels, *_ = mixture
    a = GMMClusterer(n_components=3, engine="numba").cluster(x, np.random.default_rng(5))
    b = GMMClusterer(n_components=3, engine="sklearn").cluster(x, np.random.default_rng(5))
    assert _agreement(b, a, 3) >= 0.99
    assert _agreement(labels, a, 3) >= 0.99


def _numpy_em_iteration(x, resp, reg):
    """Textbook EM step in plain numpy: M-step from resp, E-step, M-step."""
    def m_step(r):
        nk = r.sum(axis=0) + 10 * np.finfo(float).eps
        mu = r.T @ x / nk[:, None]
        cov = np.empty((r.shape[1], D, D))
        for c in range(r.shape[1]):
            diff = x - mu[c]
            cov[c] = (r[:, c, None] * diff).T @ diff / nk[c] + reg * np.eye(D)
        return nk / x.shape[0], mu, cov

    w, mu, cov = m_step(resp)
    logp = np.empty_like(resp)
    for c in range(resp.shape[1]):
        diff = x - mu[c]
        maha = np.einsum("ij,ij->i", diff @ np.linalg.inv(cov[c]), diff)
        logp[:, c] = np.log(w[c]) - 0.5 * (D * np.log(2 * np.pi) + np.linalg.slogdet(cov[c])[1] + maha)
    top = logp.max(axis=1, keepdims=True)
    log_norm = top + np.log(np.exp(logp - top).sum(axis=1, keepdims=True))
    return m_step(np.exp(logp - log_norm))


def test_one_numba_em_iteration_equals_a_numpy_em_iteration_from_the_same_responsibilities():
    rng = np.random.default_rng(2)
    x = rng.standard_normal((800, D)) @ rng.standard_normal((D, D)) + 2.0
    resp = rng.dirichlet(np.ones(4), size=800)
    w, mu, cov = em_iteration(x, resp, 1e-6)
    w_ref, mu_ref, cov_ref = _numpy_em_iteration(x, resp, 1e-6)
    np.testing.assert_allclose(w, w_ref, rtol=0, atol=1e-10)
    np.testing.assert_allclose(mu, mu_ref, rtol=0, atol=1e-10)
    np.testing.assert_allclose(cov, cov_ref, rtol=0, atol=1e-10)


def test_final_log_likelihood_matches_scikit_learn_from_the_same_kmeans_start():
    x = _curved_cloud(np.random.default_rng(4), 5000)
    resp0 = one_hot(kmeans_labels(x, 6, np.random.default_rng(9)), 6)
    fit = em_fit(x, resp0, reg_covar=1e-6, tol=1e-3, max_iter=100)
    w0, mu0, cov0, _ = m_step(x, resp0, 1e-6)
    gm = GaussianMixture(6, covariance_type="full", tol=1e-3, max_iter=100, reg_covar=1e-6,
                         weights_init=w0, means_init=mu0, precisions_init=np.linalg.inv(cov0)).fit(x)
    assert fit["n_iter"] > 2 and fit["converged"]
    assert abs(fit["log_likelihood"] - gm.score(x)) < 1e-3


def _inertia(x, labels):
    return sum(((x[labels == c] - x[labels == c].mean(axis=0)) ** 2).sum() for c in np.unique(labels))


def _curved_cloud(rng, n):
    """A curved, elongated 6-D cloud like an IOD particle cloud, standardised."""
    t = rng.uniform(-1, 1, n)
    x = np.column_stack([t, t**2, np.sin(3 * t), t**3, 0.5 * t, np.cos(2 * t)])
    x += 0.05 * rng.standard_normal(x.shape)
    return (x - x.mean(axis=0)) / x.std(axis=0)


def test_numba_kmeans_finds_the_separated_clusters(mixture):
    x, labels, *_ = mixture
    found = kmeans_labels(x, 3, np.random.default_rng(0))
    assert _agreement(labels, found, 3) >= 0.99


def test_numba_kmeans_start_is_as_good_as_scikit_learns_kmeans_on_average():
    from sklearn.cluster import KMeans
    x = _curved_cloud(np.random.default_rng(6), 3000)
    ours = np.mean([_inertia(x, kmeans_labels(x, 6, np.random.default_rng(s))) for s in range(8)])
    theirs = np.mean([KMeans(6, n_init=1, random_state=s).fit(x).inertia_ for s in range(8)])
    assert ours <= 1.02 * theirs


@pytest.mark.parametrize("init", ["kmeans", "kmeans-numba"])
def test_numba_engine_is_reproducible_for_a_fixed_seed(mixture, init):
    x = mixture[0]
    g = GMMClusterer(n_components=4, engine="numba", init=init)
    a = g.cluster(x, np.random.default_rng(8))
    b = g.cluster(x, np.random.default_rng(8))
    np.testing.assert_array_equal(a, b)


def test_component_with_no_responsibility_is_dropped_without_nan():
    rng = np.random.default_rng(1)
    x = rng.standard_normal((300, D))
    resp = np.zeros((300, 3))
    resp[:150, 0] = 1.0
    resp[150:, 1] = 1.0
    fit = em_fit(x, resp, reg_covar=1e-6, tol=1e-3, max_iter=50)
    assert list(fit["active"]) == [True, True, False]
    assert fit["weights"][2] == 0.0
    assert np.isfinite(fit["log_likelihood"])
    assert set(np.unique(predict_labels(x, fit))) <= {0, 1}


def test_numba_engine_handles_duplicated_particles():
    x = np.repeat(np.random.default_rng(0).standard_normal((3, D)), 400, axis=0)
    labels = GMMClusterer(n_components=6, engine="numba").cluster(x, np.random.default_rng(0))
    assert len(np.unique(labels)) == 3


def test_numba_engine_rejects_initialisations_it_does_not_implement():
    with pytest.raises(ParameterError, match="init"):
        GMMClusterer(engine="numba", init="random")
    with pytest.raises(ParameterError, match="init"):
        GMMClusterer(engine="sklearn", init="kmeans-numba")


def test_engines_end_at_the_same_mixture_for_the_same_generator():
    """Same subsample, same k-means seed: the labels of a curved cloud agree (rounding aside)."""
    x = _curved_cloud(np.random.default_rng(12), 8000)
    a = GMMClusterer(engine="numba").cluster(x, np.random.default_rng(3))
    b = GMMClusterer(engine="sklearn").cluster(x, np.random.default_rng(3))
    assert _agreement(b, a, 6) >= 0.999


def test_numba_kmeans_initialisation_gives_a_valid_partition(mixture):
    x, labels, *_ = mixture
    a = GMMClusterer(n_components=3, engine="numba", init="kmeans-numba").cluster(x, np.random.default_rng(2))
    assert _agreement(labels, a, 3) >= 0.99
