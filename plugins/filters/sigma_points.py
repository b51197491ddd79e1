"""Merwe's scaled sigma points (van der Merwe 2004) for the PGM's iterated component update.

The same points and weights as filterpy's ``MerweScaledSigmaPoints`` (the UKF plugin keeps using
filterpy's), computed here because importing ``filterpy.kalman`` costs about 0.7 s of CPU
(filterpy.stats imports scipy.stats and matplotlib), more than a quarter of Example 1's run, for
a dozen lines of arithmetic. ``tests/filters/test_sigma_points.py`` checks them against
filterpy's bit for bit.

With lambda = alpha^2 (n + kappa) - n and U the upper Cholesky factor of (n + lambda) P
(``scipy.linalg.cholesky``'s numbers, from :func:`cistrack.numerics.cholesky.upper_cholesky`):
the 2n + 1 points are x, x + U[k], x - U[k] (rows k of U); the mean weights are lambda / (n + lambda) for x and 1 / (2 (n + lambda)) for the others, and the
covariance weights add 1 - alpha^2 + beta to the first.
"""
from __future__ import annotations

import numpy as np

from cistrack.numerics.cholesky import upper_cholesky

__all__ = ["MerweSigmaPoints", "merwe_points"]


class MerweSigmaPoints:
    """Scaled sigma points of an n-dimensional Gaussian.

    Attributes: ``n``, ``alpha``, ``beta``, ``kappa``; ``Wm`` (2n+1,) mean weights and ``Wc``
    (2n+1,) covariance weights.
    """

    def __init__(self, n: int, alpha: float, beta: float, kappa: float):
        self.n, self.alpha, self.beta, self.kappa = n, alpha, beta, kappa
        lam = alpha ** 2 * (n + kappa) - n
        c = 0.5 / (n + lam)
        self.Wc = np.full(2 * n + 1, c)
        self.Wm = np.full(2 * n + 1, c)
        self.Wc[0] = lam / (n + lam) + (1 - alpha ** 2 + beta)
        self.Wm[0] = lam / (n + lam)

    def num_sigmas(self) -> int:
        return 2 * self.n + 1

    def sigma_points(self, x: np.ndarray, P: np.ndarray) -> np.ndarray:
        """Points (2n+1, n) of mean ``x`` (n,) and covariance ``P`` (n, n)."""
        n = self.n
        x = np.asarray(x, dtype=float).reshape(n)
        lam = self.alpha ** 2 * (n + self.kappa) - n
        return merwe_points(x, upper_cholesky((lam + n) * np.atleast_2d(P)))

    def sigma_points_batch(self, x: np.ndarray, P: np.ndarray) -> np.ndarray:
        """Points (M, 2n+1, n) of M Gaussians of means ``x`` (M, n) and covariances ``P`` (M, n, n):
        each as :meth:`sigma_points` gives it."""
        n = self.n
        x = np.asarray(x, dtype=float).reshape(-1, n)
        lam = self.alpha ** 2 * (n + self.kappa) - n
        U = upper_cholesky((lam + n) * np.asarray(P, dtype=float).reshape(-1, n, n))
        sigmas = np.empty((x.shape[0], 2 * n + 1, n))
        sigmas[:, 0] = x
        sigmas[:, 1:n + 1] = np.subtract(x[:, None, :], -U)
        sigmas[:, n + 1:] = np.subtract(x[:, None, :], U)
        return sigmas


def merwe_points(x: np.ndarray, U: np.ndarray) -> np.ndarray:
    """The 2n+1 points (2n+1, n): ``x`` (n,), then x - (-U[k]) and x - U[k] for the rows of ``U``
    (n, n): filterpy's row subtractions, done as two array operations (the same numbers)."""
    n = U.shape[0]
    sigmas = np.zeros((2 * n + 1, n))
    sigmas[0] = x
    sigmas[1:n + 1] = np.subtract(x, -U)
    sigmas[n + 1:] = np.subtract(x, U)
    return sigmas
