"""Full-covariance Gaussian-mixture EM compiled with numba (the "numba" engine of GMMClusterer).

Same model and stopping rule as scikit-learn's ``GaussianMixture(covariance_type="full")``:

* M-step: N_k = sum_i r_ik + 10 eps, w_k = N_k / n, mu_k = sum_i r_ik x_i / N_k,
  C_k = sum_i r_ik (x_i - mu_k)(x_i - mu_k)^T / N_k + reg_covar I.
* E-step: log N(x_i | mu_k, C_k) through the Cholesky factor C_k = L_k L_k^T
  (y = L_k^{-1} (x_i - mu_k), log det C_k = 2 sum log diag L_k), responsibilities in the log
  domain with a log-sum-exp per point.
* Stop when the mean log-likelihood per point changes by less than ``tol`` between two E-steps
  (scikit-learn's rule), or after ``max_iter`` iterations; a final E-step then labels points.

Degenerate components: a component whose total responsibility N_k falls below ``MIN_WEIGHT_POINTS``
points, or whose covariance is not numerically positive definite, is dropped: its weight is set
to 0 and it is excluded from every later E-step (log weight -inf), so it never produces NaN.
(The components' N_k sum to n, so the heaviest one is never dropped for its weight; with
reg_covar > 0 its covariance is positive definite.)

Arrays: points ``x`` (n, d) float64; responsibilities (n, k); weights (k,); means (k, d);
covariances (k, d, d); ``active`` (k,) bool.
"""
from __future__ import annotations

import numba as nb
import numpy as np

__all__ = ["MIN_WEIGHT_POINTS", "em_fit", "em_iteration", "m_step", "e_step", "predict_labels"]

MIN_WEIGHT_POINTS = 1e-6
_EPS10 = 10.0 * np.finfo(np.float64).eps
_LOG_2PI = np.log(2.0 * np.pi)


@nb.njit(cache=True)
def _cholesky(a, out):
    """Lower Cholesky factor of ``a`` (d, d) into ``out``; False if ``a`` is not positive definite."""
    d = a.shape[0]
    for j in range(d):
        s = a[j, j]
        for p in range(j):
            s -= out[j, p] * out[j, p]
        if not (s > 0.0):
            return False
        ljj = np.sqrt(s)
        out[j, j] = ljj
        for i in range(j + 1, d):
            t = a[i, j]
            for p in range(j):
                t -= out[i, p] * out[j, p]
            out[i, j] = t / ljj
        for i in range(j):
            out[i, j] = 0.0
    return True


@nb.njit(cache=True)
def _m_step(x, resp, reg_covar, active, weights, means, covs):
    n, d = x.shape
    k = resp.shape[1]
    for c in range(k):
        if not active[c]:
            weights[c] = 0.0
            continue
        nk = 0.0
        mu = np.zeros(d)
        for i in range(n):
            r = resp[i, c]
            nk += r
            for a in range(d):
                mu[a] += r * x[i, a]
        nk += _EPS10
        if nk < MIN_WEIGHT_POINTS:
            active[c] = False
            weights[c] = 0.0
            continue
        for a in range(d):
            mu[a] /= nk
        cov = np.zeros((d, d))
        diff = np.empty(d)
        for i in range(n):
            r = resp[i, c]
            for a in range(d):
                diff[a] = x[i, a] - mu[a]
            for a in range(d):
                ra = r * diff[a]
                for b in range(a + 1):
                    cov[a, b] += ra * diff[b]
        for a in range(d):
            for b in range(a + 1):
                v = cov[a, b] / nk
                covs[c, a, b] = v
                covs[c, b, a] = v
            covs[c, a, a] += reg_covar
            means[c, a] = mu[a]
        weights[c] = nk / n
    return weights, means, covs


@nb.njit(cache=True)
def _e_step(x, weights, means, covs, active, log_resp):
    """Fills ``log_resp`` (n, k); returns the mean log-likelihood per point. May drop components."""
    n, d = x.shape
    k = weights.shape[0]
    chol = np.zeros((k, d, d))
    logw = np.empty(k)
    for c in range(k):
        if active[c] and not _cholesky(covs[c], chol[c]):
            active[c] = False
        if active[c] and weights[c] > 0.0:
            ld = 0.0
            for a in range(d):
                ld += np.log(chol[c, a, a])
            logw[c] = np.log(weights[c]) - 0.5 * d * _LOG_2PI - ld
        else:
            active[c] = False
            logw[c] = -np.inf
    y = np.empty(d)
    total = 0.0
    for i in range(n):
        best = -np.inf
        for c in range(k):
            if not active[c]:
                log_resp[i, c] = -np.inf
                continue
            q = 0.0
            for a in range(d):
                t = x[i, a] - means[c, a]
                for p in range(a):
                    t -= chol[c, a, p] * y[p]
                t /= chol[c, a, a]
                y[a] = t
                q += t * t
            v = logw[c] - 0.5 * q
            log_resp[i, c] = v
            if v > best:
                best = v
        s = 0.0
        for c in range(k):
            if active[c]:
                s += np.exp(log_resp[i, c] - best)
        lse = best + np.log(s)
        total += lse
        for c in range(k):
            log_resp[i, c] -= lse
    return total / n


@nb.njit(cache=True)
def _em(x, resp0, reg_covar, tol, max_iter, active):
    n, d = x.shape
    k = resp0.shape[1]
    weights = np.zeros(k)
    means = np.zeros((k, d))
    covs = np.zeros((k, d, d))
    log_resp = np.empty((n, k))
    resp = np.empty((n, k))
    _m_step(x, resp0, reg_covar, active, weights, means, covs)
    lower = -np.inf
    converged = False
    n_iter = 0
    for it in range(max_iter):
        n_iter = it + 1
        prev = lower
        lower = _e_step(x, weights, means, covs, active, log_resp)
        for i in range(n):
            for c in range(k):
                resp[i, c] = np.exp(log_resp[i, c]) if active[c] else 0.0
        _m_step(x, resp, reg_covar, active, weights, means, covs)
        if abs(lower - prev) < tol:
            converged = True
            break
    final = _e_step(x, weights, means, covs, active, log_resp)
    return weights, means, covs, lower, final, n_iter, converged


@nb.njit(cache=True)
def _labels(x, weights, means, covs, active):
    n = x.shape[0]
    k = weights.shape[0]
    log_resp = np.empty((n, k))
    _e_step(x, weights, means, covs, active.copy(), log_resp)
    out = np.empty(n, dtype=np.intp)
    for i in range(n):
        b = 0
        for c in range(1, k):
            if log_resp[i, c] > log_resp[i, b]:
                b = c
        out[i] = b
    return out


def _active_from(resp: np.ndarray) -> np.ndarray:
    active = np.ones(resp.shape[1], dtype=np.bool_)
    return active


def m_step(x: np.ndarray, resp: np.ndarray, reg_covar: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(weights (k,), means (k, d), covariances (k, d, d), active (k,)) from responsibilities (n, k)."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    resp = np.ascontiguousarray(resp, dtype=np.float64)
    k, d = resp.shape[1], x.shape[1]
    active = _active_from(resp)
    w, m, c = _m_step(x, resp, float(reg_covar), active, np.zeros(k), np.zeros((k, d)), np.zeros((k, d, d)))
    return w, m, c, active


def e_step(x: np.ndarray, weights: np.ndarray, means: np.ndarray, covs: np.ndarray,
           active: np.ndarray | None = None) -> tuple[float, np.ndarray]:
    """(mean log-likelihood per point, log responsibilities (n, k)) for the given mixture."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    k = len(weights)
    act = np.ones(k, dtype=np.bool_) if active is None else np.array(active, dtype=np.bool_)
    log_resp = np.empty((x.shape[0], k))
    ll = _e_step(x, np.asarray(weights, float), np.ascontiguousarray(means, float),
                 np.ascontiguousarray(covs, float), act, log_resp)
    return float(ll), log_resp


def em_iteration(x: np.ndarray, resp: np.ndarray, reg_covar: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One EM iteration from responsibilities ``resp`` (n, k): M-step, E-step, M-step.

    Returns the (weights (k,), means (k, d), covariances (k, d, d)) after the second M-step, i.e.
    the parameters after one full iteration started from the mixture that ``resp`` defines.
    """
    w, m, c, active = m_step(x, resp, reg_covar)
    _, log_resp = e_step(x, w, m, c, active)
    r = np.where(active[None, :], np.exp(log_resp), 0.0)
    w, m, c, _ = m_step(x, r, reg_covar)
    return w, m, c


def em_fit(x: np.ndarray, resp0: np.ndarray, reg_covar: float, tol: float, max_iter: int) -> dict:
    """EM from initial responsibilities ``resp0`` (n, k) on points ``x`` (n, d).

    Returns a dict: weights (k,), means (k, d), covariances (k, d, d), active (k,) bool,
    lower_bound (mean log-likelihood per point at the last convergence check), log_likelihood
    (mean log-likelihood per point of the final parameters), n_iter, converged.
    """
    x = np.ascontiguousarray(x, dtype=np.float64)
    resp0 = np.ascontiguousarray(resp0, dtype=np.float64)
    active = _active_from(resp0)
    w, m, c, lower, final, n_iter, conv = _em(x, resp0, float(reg_covar), float(tol), int(max_iter), active)
    return {"weights": w, "means": m, "covariances": c, "active": active, "lower_bound": float(lower),
            "log_likelihood": float(final), "n_iter": int(n_iter), "converged": bool(conv)}


def predict_labels(x: np.ndarray, fit: dict) -> np.ndarray:
    """Most probable component (n,) of each point ``x`` (n, d) under a fit from :func:`em_fit`."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    return _labels(x, fit["weights"], fit["means"], fit["covariances"], fit["active"])
