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

The k-means start (``init="kmeans-numba"``) is in :mod:`.kmeans_numba`.

Arrays: points ``x`` (n, d) float64; responsibilities (n, k); weights (k,); means (k, d);
covariances (k, d, d); ``active`` (k,) bool.
"""
from __future__ import annotations

import numba as nb
import numpy as np

__all__ = ["MIN_WEIGHT_POINTS", "em_fit", "em_iteration", "m_step", "e_step", "predict_labels",
           "one_hot"]

MIN_WEIGHT_POINTS = 1e-6
_EPS10 = 10.0 * np.finfo(np.float64).eps
_LOG_2PI = np.log(2.0 * np.pi)
# Responsibilities below exp(-700) ~ 1e-304 are set to 0: they change nothing at double precision,
# and subnormal numbers they would otherwise produce make the arithmetic ~10x slower.
_LOG_TINY = -700.0


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


# No fast-math flags: with "reassoc" the numbers depended on whether these functions were compiled
# in the running process or loaded from numba's cache (the optimiser re-associates differently in
# the two contexts), so the same seed gave different mixtures. See
# cistrack.propagation.dop853_source.DEFAULT_FASTMATH. The long sums of the M-step keep their
# speed through _dot's fixed eight-way split instead (SIMD-friendly, same order every time).


@nb.njit(cache=True)
def _dot(a, b):
    """sum_i a[i] * b[i] for (n,) arrays, as eight interleaved partial sums added in a fixed order."""
    n = a.shape[0]
    s0 = s1 = s2 = s3 = s4 = s5 = s6 = s7 = 0.0
    m = n - n % 8
    for i in range(0, m, 8):
        s0 += a[i] * b[i]
        s1 += a[i + 1] * b[i + 1]
        s2 += a[i + 2] * b[i + 2]
        s3 += a[i + 3] * b[i + 3]
        s4 += a[i + 4] * b[i + 4]
        s5 += a[i + 5] * b[i + 5]
        s6 += a[i + 6] * b[i + 6]
        s7 += a[i + 7] * b[i + 7]
    for i in range(m, n):
        s0 += a[i] * b[i]
    return ((s0 + s1) + (s2 + s3)) + ((s4 + s5) + (s6 + s7))


@nb.njit(cache=True)
def _m_step(xt, resp, reg_covar, active, weights, means, covs):
    """M-step on points ``xt`` (d, n) and responsibilities ``resp`` (k, n), in place."""
    d, n = xt.shape
    k = resp.shape[0]
    diff = np.empty((d, n))
    rd = np.empty(n)
    for c in range(k):
        if not active[c]:
            weights[c] = 0.0
            continue
        r = resp[c]
        nk = 0.0
        for i in range(n):
            nk += r[i]
        nk += _EPS10
        if nk < MIN_WEIGHT_POINTS:
            active[c] = False
            weights[c] = 0.0
            continue
        for a in range(d):
            xa = xt[a]
            mu = _dot(r, xa) / nk
            means[c, a] = mu
            da = diff[a]
            for i in range(n):
                da[i] = xa[i] - mu
        for a in range(d):
            da = diff[a]
            for i in range(n):
                rd[i] = r[i] * da[i]
            for b in range(a + 1):
                v = _dot(rd, diff[b]) / nk
                covs[c, a, b] = v
                covs[c, b, a] = v
            covs[c, a, a] += reg_covar
        weights[c] = nk / n
    return weights, means, covs


@nb.njit(cache=True)
def _e_step(xt, weights, means, covs, active, log_resp):
    """Fills ``log_resp`` (k, n) for points ``xt`` (d, n); returns the mean log-likelihood per
    point. Components whose covariance is not positive definite are dropped."""
    d, n = xt.shape
    k = weights.shape[0]
    chol = np.zeros((d, d))
    y = np.empty((d, n))
    for c in range(k):
        lr = log_resp[c]
        if active[c] and not _cholesky(covs[c], chol):
            active[c] = False
        if not (active[c] and weights[c] > 0.0):
            active[c] = False
            for i in range(n):
                lr[i] = -np.inf
            continue
        ld = 0.0
        for a in range(d):
            ld += np.log(chol[a, a])
        logw = np.log(weights[c]) - 0.5 * d * _LOG_2PI - ld
        for i in range(n):
            lr[i] = 0.0
        for a in range(d):
            ya = y[a]
            xa = xt[a]
            mu = means[c, a]
            inv = 1.0 / chol[a, a]
            for i in range(n):
                ya[i] = xa[i] - mu
            for p in range(a):
                lap = chol[a, p]
                yp = y[p]
                for i in range(n):
                    ya[i] -= lap * yp[i]
            for i in range(n):
                t = ya[i] * inv
                ya[i] = t
                lr[i] += t * t
        for i in range(n):
            lr[i] = logw - 0.5 * lr[i]
    best = np.full(n, -np.inf)
    for c in range(k):
        if active[c]:
            lr = log_resp[c]
            for i in range(n):
                if lr[i] > best[i]:
                    best[i] = lr[i]
    tot = np.zeros(n)
    for c in range(k):
        if active[c]:
            lr = log_resp[c]
            for i in range(n):
                v = lr[i] - best[i]
                if v > _LOG_TINY:
                    tot[i] += np.exp(v)
    total = 0.0
    for i in range(n):
        v = best[i] + np.log(tot[i])
        tot[i] = v
        total += v
    for c in range(k):
        if active[c]:
            lr = log_resp[c]
            for i in range(n):
                lr[i] -= tot[i]
    return total / n


@nb.njit(cache=True)
def _em(xt, resp0, reg_covar, tol, max_iter, active):
    d, n = xt.shape
    k = resp0.shape[0]
    weights = np.zeros(k)
    means = np.zeros((k, d))
    covs = np.zeros((k, d, d))
    log_resp = np.empty((k, n))
    resp = np.zeros((k, n))
    _m_step(xt, resp0, reg_covar, active, weights, means, covs)
    lower = -np.inf
    converged = False
    n_iter = 0
    for it in range(max_iter):
        n_iter = it + 1
        prev = lower
        lower = _e_step(xt, weights, means, covs, active, log_resp)
        for c in range(k):
            if active[c]:
                for i in range(n):
                    v = log_resp[c, i]
                    resp[c, i] = np.exp(v) if v > _LOG_TINY else 0.0
            else:
                for i in range(n):
                    resp[c, i] = 0.0
        _m_step(xt, resp, reg_covar, active, weights, means, covs)
        if abs(lower - prev) < tol:
            converged = True
            break
    final = _e_step(xt, weights, means, covs, active, log_resp)
    return weights, means, covs, lower, final, n_iter, converged


@nb.njit(cache=True)
def _labels(xt, weights, means, covs, active):
    d, n = xt.shape
    k = weights.shape[0]
    log_resp = np.empty((k, n))
    _e_step(xt, weights, means, covs, active.copy(), log_resp)
    out = np.zeros(n, dtype=np.intp)
    best = log_resp[0].copy()
    for c in range(1, k):
        lr = log_resp[c]
        for i in range(n):
            if lr[i] > best[i]:
                best[i] = lr[i]
                out[i] = c
    return out


def _t(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(np.asarray(a, dtype=np.float64).T)


def _active_from(resp: np.ndarray) -> np.ndarray:
    active = np.ones(resp.shape[1], dtype=np.bool_)
    return active


def m_step(x: np.ndarray, resp: np.ndarray, reg_covar: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(weights (k,), means (k, d), covariances (k, d, d), active (k,)) from responsibilities (n, k)."""
    k, d = resp.shape[1], x.shape[1]
    active = _active_from(resp)
    w, m, c = _m_step(_t(x), _t(resp), float(reg_covar), active, np.zeros(k), np.zeros((k, d)), np.zeros((k, d, d)))
    return w, m, c, active


def e_step(x: np.ndarray, weights: np.ndarray, means: np.ndarray, covs: np.ndarray,
           active: np.ndarray | None = None) -> tuple[float, np.ndarray]:
    """(mean log-likelihood per point, log responsibilities (n, k)) for the given mixture."""
    k = len(weights)
    act = np.ones(k, dtype=np.bool_) if active is None else np.array(active, dtype=np.bool_)
    log_resp = np.empty((k, x.shape[0]))
    ll = _e_step(_t(x), np.asarray(weights, float), np.ascontiguousarray(means, float),
                 np.ascontiguousarray(covs, float), act, log_resp)
    return float(ll), log_resp.T


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
    active = _active_from(resp0)
    w, m, c, lower, final, n_iter, conv = _em(_t(x), _t(resp0), float(reg_covar), float(tol), int(max_iter), active)
    return {"weights": w, "means": m, "covariances": c, "active": active, "lower_bound": float(lower),
            "log_likelihood": float(final), "n_iter": int(n_iter), "converged": bool(conv)}


def predict_labels(x: np.ndarray, fit: dict) -> np.ndarray:
    """Most probable component (n,) of each point ``x`` (n, d) under a fit from :func:`em_fit`."""
    return _labels(_t(x), fit["weights"], fit["means"], fit["covariances"], fit["active"])


def one_hot(labels: np.ndarray, k: int) -> np.ndarray:
    """Responsibilities (n, k) that put each point wholly in its label's component."""
    resp = np.zeros((labels.shape[0], k))
    resp[np.arange(labels.shape[0]), labels] = 1.0
    return resp
