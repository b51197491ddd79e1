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

__all__ = ["PosteriorLinearization", "posterior_linearization_update"]


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
    """Symmetric positive semi-definite part of a small square matrix (negative eigenvalues -> 0)."""
    a = 0.5 * (a + a.T)
    w, v = np.linalg.eigh(a)
    if np.all(w >= 0):
        return a
    return (v * np.maximum(w, 0.0)) @ v.T


def _linear_regression(points: MerweScaledSigmaPoints, x: np.ndarray, P: np.ndarray,
                       residual_to_z: Callable[[np.ndarray], np.ndarray]):
    """Statistical linear regression of h over the sigma points of N(x, P), in the chart
    d = h - z centred on the measurement: d ≈ A (x' - x) + dbar, residual covariance Omega.

    Returns A (m, d), dbar (m,), Omega (m, m), Pdd (m, m).

    The Merwe points are x and x ± U_k (rows of U, U^T U = (n + lambda) P), so
    P^-1 Pxd = M^-1 (d+ - d-) / 2 with M the matrix of rows U_k: A is the central difference of h
    along the sigma directions, with no inverse of the (possibly very ill-conditioned) P.
    """
    n = x.size
    sig = points.sigma_points(x, P)
    d = np.asarray(residual_to_z(sig), dtype=float)
    if not np.all(np.isfinite(d)):
        raise FilterError("the sensor returned NaN predicted measurements at a sigma point")
    dbar = points.Wm @ d
    dd = d - dbar
    pdd = (dd.T * points.Wc) @ dd
    M = sig[1:n + 1] - x
    try:
        At = np.linalg.solve(M, 0.5 * (d[1:n + 1] - d[n + 1:]))
    except np.linalg.LinAlgError:
        At = np.linalg.lstsq(M, 0.5 * (d[1:n + 1] - d[n + 1:]), rcond=None)[0]
    A = At.T
    c = n + points.alpha ** 2 * (n + points.kappa) - n  # n + lambda
    AMt = A @ M.T                                       # A P A^T = (A M^T)(A M^T)^T / (n + lambda)
    omega = _psd_part(pdd - AMt @ AMt.T / c)
    return A, dbar, omega, pdd


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
    P0 = np.asarray(P0, dtype=float)
    R = np.asarray(R, dtype=float)
    xi, Pi = x0, P0
    first = None
    step = np.inf
    it = 0
    for it in range(1, max_iterations + 1):
        A, dbar, omega, pdd = _linear_regression(points, xi, Pi, residual_to_z)
        dhat = dbar + A @ (x0 - xi)         # predicted h(x0) - z under the linear model
        S = A @ P0 @ A.T + omega + R
        S = 0.5 * (S + S.T)
        if first is None:
            first = (-dbar, 0.5 * (pdd + pdd.T) + R)
        # K = P0 A^T S^-1  <=>  S K^T = A P0
        K = np.linalg.solve(S, A @ P0).T
        x = x0 - K @ dhat
        P = regularize_covariance(P0 - K @ S @ K.T, regularize)
        try:
            L = np.linalg.cholesky(P)
            step = float(np.linalg.norm(np.linalg.solve(L, x - xi)))
        except np.linalg.LinAlgError:
            step = np.inf
        xi, Pi = x, P
        last = (-dhat, S)
        if it > 1 and step < tolerance:
            break
    return PosteriorLinearization(xi, Pi, it, step, first[0], first[1], last[0], last[1])
