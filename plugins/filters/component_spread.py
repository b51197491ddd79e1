"""Moment-preserving shrinkage of clustered components toward their common mean.

A hard partition (k-means cells) of a cloud gives components that are truncated pieces of it:
each piece's covariance lacks the spread along the directions that separate it from its
neighbours. Conditioned on a measurement oblique to those directions, a piece then claims a
conditional covariance smaller than the cloud's (for a Gaussian cut into cells, the piece's
conditional variance grows with its length along the cut, so a shorter piece is narrower),
and repeated updates compound it: on a linear-Gaussian problem (6-D, one coordinate measured
15 times, 8 seeds) a 6-component PGM ended with mean NEES 16.7 against 7.1 for the exact
Kalman filter, while one component matched it (7.0).

The shrinkage (as in Liu and West's kernel shrinkage for particle filters) moves each mean
toward the mixture mean and gives the lost spread back to every component:

    mu_i' = mu + lam (mu_i - mu),   P_i' = P_i + (1 - lam^2) B,   B = sum_i w_i (mu_i - mu)(mu_i - mu)^T

which keeps the mixture's mean and covariance exactly (sum w_i P_i' + lam^2 B = W + B). lam = 1
is the plain partition, lam = 0 a single Gaussian (the UKF's belief).
"""
from __future__ import annotations

import numpy as np

__all__ = ["shrink_components"]


def shrink_components(weights: np.ndarray, means: np.ndarray, covs: np.ndarray,
                      kept_spread: float) -> tuple[np.ndarray, np.ndarray]:
    """Shrink components (weights (M,), means (M, d), covs (M, d, d)) toward their mixture mean,
    keeping ``kept_spread`` = lam^2 in [0, 1] of the between-component covariance as spread of
    the means and adding the rest to every covariance. Returns (means (M, d), covs (M, d, d))."""
    w = np.asarray(weights, dtype=float)
    w = w / w.sum()
    mu = w @ means
    dm = means - mu
    B = (dm * w[:, None]).T @ dm
    lam = np.sqrt(kept_spread)
    return mu + lam * dm, covs + (1.0 - kept_spread) * B[None]
