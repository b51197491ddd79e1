"""The predictive measurement mixture of a Gaussian-mixture belief, and the tail probability of
an observed measurement under it.

Each component (weight w_k, mean x_k, covariance P_k) is pushed through the sensor by the
unscented transform: the 2d sigma points ``x_k ± sqrt(d) s_i`` (``s_i`` the columns of a square
root of P_k; :func:`cistrack.least_squares.unscented_prediction.sigma_points`), measured, with
equal weights 1/(2d), give the predicted mean and covariance; with the noise R that is the
component N(zhat_k, S_k), S_k = P_zz,k + R. Everything is computed in residual coordinates
``zhat - z`` (angles wrapped by the sensor), so the observation sits at 0.

The tail probability ``p = P(log f(Z) <= log f(z))``, Z drawn from the predictive mixture f:

* an analytic upper bound, exact for one component: f >= w_k N_k everywhere, so the event
  {f(Z) <= f(z)} lies inside {w_k N_k(Z) <= f(z)}, whose probability under component k is
  ``P(chi2(m) >= r_k)`` with ``r_k = 2 (log w_k + log N_k(mode) - log f(z))``; hence
  ``p <= sum_k w_k P(chi2(m) >= r_k)``. It is tight where the components are apart or z lies in
  the far tail, and is never below p (a detector using it errs towards fewer alarms);
* a Monte Carlo estimate, ``(count + 1) / (n + 1)`` over n draws of a generator seeded from
  (``seed``, the bits of t): the same inputs give the same p in every process. It resolves the
  bulk, where the bound is loose, and cannot go below 1 / (n + 1).

:func:`tail_probability` returns the smaller of the two (the bound alone for one component or
``n_draws = 0``).
"""
from __future__ import annotations

import math

import numpy as np

from cistrack.least_squares.unscented_prediction import sigma_points
from cistrack.model.belief import GaussianMixture, regularize_covariance
from cistrack.model.innovation import block_diagonal

__all__ = ["predictive_mixture", "tail_probability", "state_mixture"]

_LOG_2PI = math.log(2.0 * math.pi)


def state_mixture(prior) -> GaussianMixture:
    """The prior's mixture when it has one of the samples' dimension with finite numbers, else
    one Gaussian moment-matched to the samples."""
    mix = getattr(prior, "mixture", None)
    d = np.asarray(prior.samples.states).shape[1]
    if isinstance(mix, GaussianMixture) and mix.dim == d and np.all(np.isfinite(mix.means)) \
            and np.all(np.isfinite(mix.covariances)):
        return mix
    return prior.samples.moment_match()


def _measured_residuals(points: np.ndarray, group, sensor) -> tuple[np.ndarray, np.ndarray]:
    """``zhat - z`` (wrapped) of every point for the stacked measurements (P, sum m), and R."""
    cols_out, noises = [], []
    for m in group:
        own = sensor.for_measurement(m) if hasattr(sensor, "for_measurement") else sensor
        names = tuple(own.names)
        cols = np.array([names.index(n) for n in m.names], dtype=np.intp)
        full_z = np.zeros(len(names))
        full_z[cols] = np.asarray(m.z, dtype=float)
        zs = np.asarray(own.measure(points, m.t), dtype=float)
        cols_out.append(np.asarray(own.residual(zs, full_z[None, :]), dtype=float)[:, cols])
        noises.append(np.atleast_2d(np.asarray(m.covariance, dtype=float)))
    return np.concatenate(cols_out, axis=1), block_diagonal(noises)


def predictive_mixture(prior, group, sensor) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The predictive mixture of ``group`` (measurements at one time) under ``prior``, in
    residual coordinates: weights (M,), means (M, m) of ``zhat - z``, covariances S (M, m, m)."""
    mix = state_mixture(prior)
    d = mix.dim
    points = np.concatenate([sigma_points(mix.means[k], regularize_covariance(mix.covariances[k]))
                             for k in range(mix.n_components)])
    res, noise = _measured_residuals(points, group, sensor)
    res = res.reshape(mix.n_components, 2 * d, -1)
    means = res.mean(axis=1)
    dev = res - means[:, None, :]
    covs = np.einsum("kpi,kpj->kij", dev, dev) / (2 * d) + noise[None]
    return mix.weights.copy(), means, regularize_covariance(covs)


def _component_logpdf(x: np.ndarray, means: np.ndarray, chol: np.ndarray) -> np.ndarray:
    """log N(x_i; mu_k, L_k L_k^T) for points x (N, m): (N, M)."""
    m = means.shape[1]
    diff = x[None, :, :] - means[:, None, :]                       # (M, N, m)
    white = np.linalg.solve(chol, np.swapaxes(diff, 1, 2))          # (M, m, N)
    logdet = np.sum(np.log(np.diagonal(chol, axis1=1, axis2=2)), axis=1)
    q = np.sum(white * white, axis=1)                               # (M, N)
    return (-0.5 * q - logdet[:, None] - 0.5 * m * _LOG_2PI).T


def _logsumexp(a: np.ndarray, axis: int) -> np.ndarray:
    top = np.max(a, axis=axis, keepdims=True)
    top = np.where(np.isfinite(top), top, 0.0)
    return np.squeeze(top, axis=axis) + np.log(np.sum(np.exp(a - top), axis=axis))


def _log_bound(weights: np.ndarray, chol: np.ndarray, log_f: float, m: int) -> float:
    """ln of sum_k w_k P(chi2(m) >= r_k), the analytic upper bound on p."""
    from .sequential import chi2_log10_sf

    logdet = np.sum(np.log(np.diagonal(chol, axis1=1, axis2=2)), axis=1)
    with np.errstate(divide="ignore"):
        logw = np.log(weights)
    r = 2.0 * (logw - logdet - 0.5 * m * _LOG_2PI - log_f)
    terms = np.array([lw + math.log(10.0) * chi2_log10_sf(float(rk), m) for lw, rk in zip(logw, r)])
    return float(min(0.0, _logsumexp(terms, axis=0)))


def _seed_words(seed: int, t: float) -> list[int]:
    bits = int(np.array(t, dtype=np.float64).view(np.uint64))
    return [int(seed), bits >> 32, bits & 0xFFFFFFFF]


def tail_probability(weights: np.ndarray, means: np.ndarray, covs: np.ndarray, n_draws: int, seed: int,
                     t: float) -> tuple[float, dict]:
    """ln p, p = P(log f(Z) <= log f(0)) under the mixture (weights, means, covs) (see the module
    docstring), and the parts for reports: {"log_density", "log_p_bound", "log_p_mc"}."""
    m = means.shape[1]
    chol = np.linalg.cholesky(covs)
    with np.errstate(divide="ignore"):
        logw = np.log(weights)
    log_f = float(_logsumexp(_component_logpdf(np.zeros((1, m)), means, chol)[0] + logw, axis=0))
    log_bound = _log_bound(weights, chol, log_f, m)
    out = {"log_density": log_f, "log_p_bound": log_bound, "log_p_mc": float("nan")}
    if means.shape[0] == 1 or n_draws == 0:
        return log_bound, out
    rng = np.random.default_rng(_seed_words(seed, t))
    labels = np.sort(rng.choice(weights.shape[0], size=n_draws, p=weights))
    z = means[labels] + np.einsum("nij,nj->ni", chol[labels], rng.standard_normal((n_draws, m)))
    log_fz = _logsumexp(_component_logpdf(z, means, chol) + logw[None, :], axis=1)
    count = int(np.count_nonzero(log_fz <= log_f))
    out["log_p_mc"] = math.log((count + 1) / (n_draws + 1))
    return min(log_bound, out["log_p_mc"]), out
