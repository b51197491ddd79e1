"""The kernel (ensemble Gaussian mixture) update of a sharp measurement: every particle its own Gaussian.

After a long gap the PGM's cloud is a long, thin, bent filament, and the first measurements of
the next pass are far sharper than it (likelihood ESS below a few per cent of the particles). A
Gaussian fitted to a cluster of it is wider than the filament across and bent along it, so a
Kalman update of that Gaussian lands off the filament. Here instead each particle x_j carries a
narrow Gaussian kernel N(x_j, B_c) whose covariance is its cluster's sample covariance P_c
scaled by Silverman's bandwidth for the cluster's n_c particles in d dimensions,

    B_c = beta^2 P_c,    beta^2 = (4 / (n_c (d + 2)))^(2 / (d + 4)),

so the prior is the kernel density estimate of the particles (the ensemble Gaussian mixture
filter's prior, with local rather than one global covariance). Each kernel is conditioned on the
measurement by an iterated extended Kalman update (measurement Jacobian by central differences at
the current linearisation point, re-linearised ``iterations`` times); its weight is the
likelihood of the measurement under the linearised kernel, N(nu; 0, S_j). The posterior is the
weighted mixture of the N conditioned kernels; N particles are drawn from it (systematic
resampling of the kernels, then one Gaussian draw from each chosen kernel's posterior).

Cost: 12 extra sensor evaluations per iteration over all particles and (N, 6, 6) linear algebra;
no propagation (Example 3: about 1-2 s more per run).

The PGM uses the kernels only in a pass that follows a gap (parameter ``kernel_ess``); why:
docs/history/pgm.md.
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

from cistrack.errors import FilterError
from cistrack.interfaces.pgm_steps import ClusteredParticles

from ..resampling import normalize_log_weights, systematic_resample

__all__ = ["silverman_factor", "kernel_update", "KERNEL_JACOBIAN_STEPS", "PassAfterGap"]

KERNEL_JACOBIAN_STEPS: np.ndarray = np.array([1e-7, 1e-7, 1e-7, 1e-5, 1e-5, 1e-5])
"""Central-difference steps (LU, VU) of the measurement Jacobian at each kernel's linearisation point."""

_LOG_2PI = float(np.log(2.0 * np.pi))


def silverman_factor(n: np.ndarray | int, d: int) -> np.ndarray:
    """Silverman's squared bandwidth beta^2 = (4 / (n (d + 2)))^(2 / (d + 4)) for n points in d dimensions."""
    n = np.maximum(np.asarray(n, dtype=float), 1.0)
    return (4.0 / (n * (d + 2.0))) ** (2.0 / (d + 4.0))


def _jacobians(residuals: Callable[[np.ndarray], np.ndarray], x: np.ndarray) -> np.ndarray:
    """d h / d x (N, m, d) at ``x`` (N, d) by central differences of ``residuals`` (h(x) - z, wrapped)."""
    n, d = x.shape
    cols = []
    for k in range(d):
        step = np.zeros(d)
        step[k] = KERNEL_JACOBIAN_STEPS[k] if d == KERNEL_JACOBIAN_STEPS.size else 1e-7
        hi = residuals(x + step)
        lo = residuals(x - step)
        cols.append((hi - lo) / (2.0 * step[k]))
    return np.stack(cols, axis=-1)


def kernel_update(prior: ClusteredParticles, residuals: Callable[[np.ndarray], np.ndarray], R: np.ndarray,
                  n_draw: int, rng: np.random.Generator, who: str, iterations: int = 3,
                  bandwidth: float | None = None) -> tuple[np.ndarray, np.ndarray, float, np.ndarray]:
    """Condition every particle's kernel on one measurement and draw ``n_draw`` posterior particles.

    Parameters
    ----------
    prior : ClusteredParticles       prior particles (N, d) (equally weighted, LU and VU), their
                                     clusters (N,) in [0, M) and the clusters' covariances (M, d, d)
    residuals : callable             (K, d) states -> (K, m) predicted minus measured (angles wrapped)
    R : (m, m) float                 measurement noise covariance
    n_draw : int                     posterior particles to draw
    rng : numpy Generator            the filter's stream
    who : str                        the filter's name, for errors
    iterations : int                 linearisations per kernel (1: extended Kalman update)
    bandwidth : float or None        beta^2; None: Silverman's for each cluster's size

    Returns
    -------
    samples (n_draw, d), their kernels' cluster labels (n_draw,), the log evidence
    log p(z) under the kernel mixture, and the kernel weights (N,) after the update.
    """
    x, labels = np.asarray(prior.states, dtype=float), prior.labels
    n, d = x.shape
    counts = np.bincount(labels, minlength=len(prior.covariances))
    beta2 = silverman_factor(counts, d) if bandwidth is None else np.full(len(counts), float(bandwidth))
    B = beta2[labels][:, None, None] * prior.covariances[labels]  # (N, d, d)
    xi, post_cov, loglik = _condition_kernels(x, B, residuals, R, iterations, who)
    logw, log_evidence = normalize_log_weights(loglik - np.log(n), who)
    w = np.exp(logw)
    pick = systematic_resample(w, n_draw, rng)
    # one draw from each chosen kernel's posterior; eigen-factorisation tolerates tiny negative parts
    vals, vecs = np.linalg.eigh(post_cov[pick])
    root = vecs * np.sqrt(np.clip(vals, 0.0, None))[:, None, :]
    eps = rng.standard_normal((n_draw, d))
    samples = xi[pick] + np.einsum("nij,nj->ni", root, eps)
    return samples, labels[pick], float(log_evidence), w


def _condition_kernels(x: np.ndarray, B: np.ndarray, residuals: Callable[[np.ndarray], np.ndarray],
                       R: np.ndarray, iterations: int, who: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Iterated extended Kalman update of the kernels N(x (N, d), B (N, d, d)): posterior means
    (N, d), covariances (N, d, d) and the log-likelihoods (N,) of the measurement under them."""
    m_rows = R.shape[0]
    xi = x.copy()
    for _ in range(iterations):
        r = residuals(xi)  # h(xi) - z
        if not np.all(np.isfinite(r)):
            raise FilterError(f"filter '{who}': the sensor returned non-finite predicted measurements "
                              "in the kernel update")
        H = _jacobians(residuals, xi)  # (N, m, d)
        # innovation linearised at xi, referred to the kernel's centre: z - h(xi) - H (x - xi)
        nu = -r - np.einsum("nmd,nd->nm", H, x - xi)
        BHt = B @ np.swapaxes(H, 1, 2)  # (N, d, m)
        S = H @ BHt + R  # (N, m, m)
        K = np.linalg.solve(S, np.swapaxes(BHt, 1, 2))  # S^-1 H B: (N, m, d)
        K = np.swapaxes(K, 1, 2)  # (N, d, m)
        xi = x + np.einsum("ndm,nm->nd", K, nu)
    post_cov = B - K @ S @ np.swapaxes(K, 1, 2)
    post_cov = 0.5 * (post_cov + np.swapaxes(post_cov, 1, 2))
    sign, logdet = np.linalg.slogdet(S)
    maha = np.einsum("nm,nm->n", nu, np.linalg.solve(S, nu[..., None])[..., 0])
    loglik = -0.5 * (maha + logdet + m_rows * _LOG_2PI)
    if not (np.all(sign > 0) and np.all(np.isfinite(loglik)) and np.all(np.isfinite(xi))):
        raise FilterError(f"filter '{who}': the kernel update produced a non-finite likelihood or mean")
    return xi, post_cov, loglik


class PassAfterGap:
    """Whether the updates are in the first pass after a gap: a gap of ``gap_days`` or more between
    updates starts such a pass, a pause of ``pause_hours`` or more ends it."""

    def __init__(self, gap_days: float, pause_hours: float) -> None:
        from cistrack import units

        self.gap_tu = float(units.days_to_tu(gap_days))
        self.pause_tu = float(units.hours_to_tu(pause_hours))
        self.t_last: float | None = None
        self.after_gap = False

    def at(self, t: float) -> bool:
        """True when an update at ``t`` (TU) is in a pass after a gap; records ``t`` as the latest update."""
        last, self.t_last = self.t_last, t
        if last is not None and t - last >= self.gap_tu:
            self.after_gap = True
        elif last is not None and t - last >= self.pause_tu:
            self.after_gap = False
        return self.after_gap
