"""Moment-preserving shrinkage of clustered components toward their common mean.

A hard partition (k-means cells) of a cloud gives components that are truncated pieces of it:
each piece's covariance lacks the spread along the directions that separate it from its
neighbours. Conditioned on a measurement oblique to those directions, a piece then claims a
conditional covariance smaller than the cloud's (for a Gaussian cut into cells, the piece's
conditional variance grows with its length along the cut, so a shorter piece is narrower),
and repeated updates compound it: the mixture ends overconfident (docs/history/pgm.md).

The shrinkage (as in Liu and West's kernel shrinkage for particle filters) moves each mean
toward the mixture mean and gives the lost spread back to every component:

    mu_i' = mu + lam (mu_i - mu),   P_i' = P_i + (1 - lam^2) B,   B = sum_i w_i (mu_i - mu)(mu_i - mu)^T

which keeps the mixture's mean and covariance exactly (sum w_i P_i' + lam^2 B = W + B). lam = 1
is the plain partition, lam = 0 a single Gaussian (the UKF's belief).

Not while reacquiring. The model above is one cloud cut into cells. After a long gap the cloud is
several hypotheses, the parts of a long arc that the line of sight may cross, spread over about
1e5 noise sigmas of predicted measurement (reacquisition_particles.py). Shrinking them pulls every
hypothesis toward their common mean, in the empty space between them, and the inflated
components reach across several line-of-sight crossings at once. The PGM therefore shrinks only
while the prior's predicted measurements spread over at most ``shrink_spread_sigma`` noise
sigmas (default 1,000, the reacquisition threshold: the same regime).
The measurements behind the default 0.7 and the reacquisition rule: docs/history/pgm.md.
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
