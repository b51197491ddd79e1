"""Iterated posterior-linearisation measurement update with Merwe scaled sigma points.

The ordinary UKF update linearises the measurement function h statistically over the *prior*.
When the prior is much wider than the measurement noise and h is curved over it (angles of a
target whose range is uncertain by tens of percent), the points that agree with the measurement
lie on a curved sliver of the prior and the prior-wide linearisation puts the posterior next to
that sliver, with a covariance far too small there: an overconfident update.

The iterated posterior linearisation (IPLF; García-Fernández, Svensson, Morelande and Särkkä,
"Posterior linearization filter: principles and implementation using sigma points", IEEE Trans.
Signal Processing 63(20), 2015) repeats the update, each time fitting h by statistical linear
regression z ≈ A x + b + e, e ~ N(0, Omega), over the sigma points of the *current posterior*
and applying that linear model to the prior:

    S = A P0 A^T + Omega + R,   K = P0 A^T S^-1,   x = x0 + K (z - A x0 - b),   P = P0 - K S K^T.

Its first iteration is the ordinary UKF update. For a linear h every iteration gives the exact
Kalman update. Omega (the regression's residual covariance) inflates S where h is still curved
over the posterior.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable

import numpy as np

from cistrack.model.belief import regularize_covariance
from cistrack.errors import FilterError

if TYPE_CHECKING:  # filterpy (and through it matplotlib) is imported only where a UKF runs
    from filterpy.kalman import MerweScaledSigmaPoints

__all__ = ["PosteriorLinearization", "posterior_linearization_update", "posterior_linearization_updates",
           "MAX_UPDATE_ITERATIONS"]

MAX_UPDATE_ITERATIONS = 1000
"""Most linearisations a filter's ``update_iterations`` may ask for: the update settles in 2-10;
more only repeats one that does not settle (each a sensor call per component), and a run asked
for a million of them took minutes per update."""


@dataclass
class PosteriorLinearization:
    """Result of :func:`posterior_linearization_update`.

    x (d,), P (d, d): posterior mean and covariance. iterations: linearisations done.
    step: Mahalanobis length (in the posterior's metric) of the last iteration's change of x.
    innovation (m,), S (m, m): the first (prior-linearised, ordinary UKF) innovation and its
    covariance, which give the measurement's predictive likelihood.
    innovation_final (m,), S_final (m, m): the same under the last (posterior) linearisation,
    z - (A x0 + b) and A P0 A^T + Omega + R: the predictive likelihood with h linearised where the
    measurement put the state rather than over the whole prior.
    """

    x: np.ndarray
    P: np.ndarray
    iterations: int
    step: float
    innovation: np.ndarray
    S: np.ndarray
    innovation_final: np.ndarray | None = None
    S_final: np.ndarray | None = None


def _psd_part(a: np.ndarray) -> np.ndarray:
    """Symmetric positive semi-definite parts of small square matrices a (M, m, m) (negative
    eigenvalues -> 0; a matrix without any is returned symmetrised, unchanged otherwise)."""
    a = 0.5 * (a + np.swapaxes(a, -1, -2))
    w, v = np.linalg.eigh(a)
    negative = np.any(w < 0, axis=-1)
    for i in np.flatnonzero(negative):
        a[i] = (v[i] * np.maximum(w[i], 0.0)) @ v[i].T
    return a


def _solve_each(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Solutions (M, n, k) of a[i] x = b[i] for a (M, n, n), b (M, n, k); a singular a[i] gets
    its least-squares solution."""
    try:
        return np.linalg.solve(a, b)
    except np.linalg.LinAlgError:
        out = np.empty(a.shape[:1] + b.shape[1:])
        for i in range(a.shape[0]):
            try:
                out[i] = np.linalg.solve(a[i], b[i])
            except np.linalg.LinAlgError:
                out[i] = np.linalg.lstsq(a[i], b[i], rcond=None)[0]
        return out


def _sigma_points(points: MerweScaledSigmaPoints, x: np.ndarray, P: np.ndarray) -> np.ndarray:
    """Sigma points (M, 2n+1, n) of the Gaussians N(x[i] (n,), P[i] (n, n))."""
    batch = getattr(points, "sigma_points_batch", None)
    if batch is not None:
        return batch(x, P)
    return np.stack([points.sigma_points(x[i], P[i]) for i in range(x.shape[0])])


def _linear_regression(points: MerweScaledSigmaPoints, x: np.ndarray, P: np.ndarray,
                       residual_to_z: Callable[[np.ndarray], np.ndarray]):
    """Statistical linear regression of h over the sigma points of each N(x[i], P[i]) (x (M, d),
    P (M, d, d)), in the chart d = h - z centred on the measurement: d ≈ A (x' - x) + dbar,
    residual covariance Omega. One call of ``residual_to_z`` for all M Gaussians' points.

    Returns A (M, m, d), dbar (M, m), Omega (M, m, m), Pdd (M, m, m).

    The Merwe points are x and x ± U_k (rows of U, U^T U = (n + lambda) P), so
    P^-1 Pxd = M^-1 (d+ - d-) / 2 with M the matrix of rows U_k: A is the central difference of h
    along the sigma directions, with no inverse of the (possibly very ill-conditioned) P.
    """
    g, n = x.shape
    sig = _sigma_points(points, x, P)
    k = sig.shape[1]
    d = np.asarray(residual_to_z(sig.reshape(g * k, n)), dtype=float)
    if not np.all(np.isfinite(d)):
        raise FilterError("the sensor returned NaN predicted measurements at a sigma point")
    d = d.reshape(g, k, -1)
    dbar = points.Wm @ d
    dd = d - dbar[:, None, :]
    pdd = (np.swapaxes(dd, 1, 2) * points.Wc) @ dd
    M = sig[:, 1:n + 1] - x[:, None, :]
    At = _solve_each(M, 0.5 * (d[:, 1:n + 1] - d[:, n + 1:]))
    A = np.swapaxes(At, 1, 2)
    c = n + points.alpha ** 2 * (n + points.kappa) - n  # n + lambda
    AMt = A @ np.swapaxes(M, 1, 2)                      # A P A^T = (A M^T)(A M^T)^T / (n + lambda)
    omega = _psd_part(pdd - AMt @ np.swapaxes(AMt, 1, 2) / c)
    return A, dbar, omega, pdd


def _mahalanobis_steps(P: np.ndarray, dx: np.ndarray) -> np.ndarray:
    """Length of each dx[i] (d,) in the metric of P[i] (d, d); inf where P[i] is not positive definite."""
    try:
        y = np.linalg.solve(np.linalg.cholesky(P), dx[..., None])[..., 0]
    except np.linalg.LinAlgError:
        if P.shape[0] == 1:
            return np.array([np.inf])
        return np.concatenate([_mahalanobis_steps(P[i:i + 1], dx[i:i + 1]) for i in range(P.shape[0])])
    return np.array([np.linalg.norm(row) for row in y])


def posterior_linearization_update(points: MerweScaledSigmaPoints, x0: np.ndarray, P0: np.ndarray,
                                   residual_to_z: Callable[[np.ndarray], np.ndarray], R: np.ndarray,
                                   max_iterations: int = 10, tolerance: float = 1e-3,
                                   regularize: float = 1e-12) -> PosteriorLinearization:
    """Condition N(x0, P0) on a measurement z through the iterated posterior linearisation.

    Parameters
    ----------
    points : Merwe scaled sigma points for the state dimension d (.sigma_points.MerweSigmaPoints
             or filterpy's MerweScaledSigmaPoints: the same points and weights)
    x0 (d,), P0 (d, d) : prior mean and covariance
    residual_to_z : states (K, d) -> h(states) - z (K, m), angles wrapped (one call per iteration)
    R (m, m) : measurement noise covariance
    max_iterations : linearisations at most (1 = the ordinary UKF update)
    tolerance : stop when the mean moved less than this many posterior standard deviations
                (Mahalanobis length) in the last iteration
    regularize : eigenvalue floor, relative to max(diag P), of the returned covariance
    """
    x0 = np.asarray(x0, dtype=float)
    return posterior_linearization_updates(points, x0.reshape(1, -1), np.asarray(P0, dtype=float)[None],
                                           residual_to_z, R, max_iterations, tolerance, regularize)[0]


def posterior_linearization_updates(points: MerweScaledSigmaPoints, x0: np.ndarray, P0: np.ndarray,
                                    residual_to_z: Callable[[np.ndarray], np.ndarray], R: np.ndarray,
                                    max_iterations: int = 10, tolerance: float = 1e-3,
                                    regularize: float = 1e-12) -> list[PosteriorLinearization]:
    """:func:`posterior_linearization_update` of M Gaussians N(x0[i] (d,), P0[i] (d, d)) with the
    same measurement: each iterates on its own (the same numbers as one at a time), and each
    iteration calls ``residual_to_z`` once, on the sigma points of all that still iterate."""
    x0 = np.asarray(x0, dtype=float)
    P0 = np.asarray(P0, dtype=float)
    R = np.asarray(R, dtype=float)
    g = x0.shape[0]
    if g == 0:
        return []
    xi, Pi = x0.copy(), P0.copy()
    steps = np.full(g, np.inf)
    its = np.zeros(g, dtype=int)
    first: list = [None] * g
    last: list = [None] * g
    active = np.arange(g)
    for it in range(1, max_iterations + 1):
        a0, p0 = x0[active], P0[active]
        A, dbar, omega, pdd = _linear_regression(points, xi[active], Pi[active], residual_to_z)
        dhat = dbar + (A @ (a0 - xi[active])[..., None])[..., 0]   # predicted h(x0) - z, linear model
        At = np.swapaxes(A, 1, 2)
        S = A @ p0 @ At + omega + R
        S = 0.5 * (S + np.swapaxes(S, 1, 2))
        # K = P0 A^T S^-1  <=>  S K^T = A P0
        K = np.swapaxes(np.linalg.solve(S, A @ p0), 1, 2)
        x = a0 - (K @ dhat[..., None])[..., 0]
        P = regularize_covariance(p0 - K @ S @ np.swapaxes(K, 1, 2), regularize, each=True)
        steps[active] = _mahalanobis_steps(P, x - xi[active])
        for j, i in enumerate(active):
            if first[i] is None:
                first[i] = (-dbar[j], 0.5 * (pdd[j] + pdd[j].T) + R)
            last[i] = (-dhat[j], S[j])
        xi[active], Pi[active], its[active] = x, P, it
        if it > 1:
            active = active[~(steps[active] < tolerance)]
        if active.size == 0:
            break
    return [PosteriorLinearization(xi[i], Pi[i], int(its[i]), float(steps[i]), first[i][0], first[i][1],
                                   last[i][0], last[i][1]) for i in range(g)]
