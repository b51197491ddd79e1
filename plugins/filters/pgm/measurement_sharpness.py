"""How sharp a measurement is against a particle cloud, and the PGM's response to a sharp one.

The effective sample size of the likelihood weights w_j = exp(-q_j / 2),
q_j = (h(x_j) - z)^T R^-1 (h(x_j) - z), says what fraction of the prior particles lie where
the measurement is: about (noise width / cloud width in measurement space)^m for m measured
components.

The PGM's response, ``split_components``: a Gaussian fitted to a smaller piece of a smoothly bent
cloud deviates from it by the curvature times the piece's size squared, so at a sharp measurement
the PGM may cluster into more, smaller components, each still large enough for a 6-D covariance
(the merge rule). Off by default; why, and Example 3's setting: docs/history/pgm.md.
"""
from __future__ import annotations

import numpy as np

__all__ = ["measurement_quadratic", "likelihood_ess_fraction"]


def measurement_quadratic(residuals: np.ndarray, R: np.ndarray) -> np.ndarray:
    """q_j = r_j^T R^-1 r_j for residuals (N, m) h(x_j) - z and noise R (m, m) -> (N,)."""
    L = np.linalg.cholesky(np.asarray(R, dtype=float))
    y = np.linalg.solve(L, np.asarray(residuals, dtype=float).T)
    return np.sum(y * y, axis=0)


def likelihood_ess_fraction(q: np.ndarray) -> float:
    """(sum w)^2 / (N sum w^2) of w = exp(-q / 2), q (N,): 1 when every particle explains the
    measurement equally, 1/N when one particle alone does."""
    q = np.asarray(q, dtype=float)
    w = np.exp(-0.5 * (q - q.min()))
    return float(w.sum() ** 2 / np.sum(w * w) / q.size)
