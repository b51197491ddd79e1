"""How many particles the PGM draws from a posterior: more while the cloud is reacquiring.

Model. After a long gap the prior cloud is spread over the whole orbit and beyond, its predicted
angles over about 1e5 noise standard deviations. One pass of measurements has to choose between
several hypotheses, the parts of the cloud that the line of sight crosses, and a single
measurement cannot tell them apart. Resampled to ``n_particles``, a hypothesis of a few percent
holds about one minimum-size cluster and is merged into a neighbour or lost to sampling noise
before later measurements can favour it (docs/history/pgm.md has the runs).

The rule. While the prior's predicted measurements at an update spread wider than
``reacquire_spread_sigma`` noise standard deviations, the posterior is resampled with
``reacquire_factor`` x ``n_particles`` particles instead of ``n_particles``. A hypothesis of
weight w then keeps that many times more particles. Once the cloud's predicted spread falls
back under the threshold, the count returns to ``n_particles`` at the next update. The spread is the largest standard deviation of
the predicted-measurement residuals in noise units, sqrt(largest eigenvalue of
R^-1/2 cov(h(x) - z) R^-1/2).

Measurements behind the default factor 4 and threshold 1,000 sigma: docs/history/pgm.md.
"""
from __future__ import annotations

import numpy as np

__all__ = ["measurement_spread_sigma", "particles_to_draw"]


def measurement_spread_sigma(residuals: np.ndarray, R: np.ndarray) -> float:
    """Largest standard deviation of predicted-measurement residuals ``residuals`` (N, m)
    (h(x) - z, angles wrapped) in units of the noise, whose covariance is ``R`` (m, m)."""
    res = np.asarray(residuals, dtype=float)
    if res.shape[0] < 2:
        return 0.0
    L = np.linalg.cholesky(0.5 * (R + R.T))
    w = np.linalg.solve(L, (res - res.mean(axis=0)).T)  # whitened residuals (m, N)
    c = np.atleast_2d(np.cov(w))
    return float(np.sqrt(max(np.linalg.eigvalsh(c).max(), 0.0)))


def particles_to_draw(spread_sigma: float, n_particles: int, factor: float, threshold_sigma: float) -> int:
    """round(factor x n_particles) while ``spread_sigma`` > ``threshold_sigma``, else
    ``n_particles``; never fewer than ``n_particles`` (a factor of 1 or less is off)."""
    if not spread_sigma > threshold_sigma:
        return n_particles
    return max(n_particles, int(round(factor * n_particles)))
