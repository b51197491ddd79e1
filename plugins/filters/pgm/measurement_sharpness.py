"""How sharp a measurement is against a particle cloud, and the PGM's response to a sharp one.

The effective sample size of the likelihood weights w_j = exp(-q_j / 2),
q_j = (h(x_j) - z)^T R^-1 (h(x_j) - z), says what fraction of the prior particles lie where
the measurement is: about (noise width / cloud width in measurement space)^m for m measured
components.

Why it matters (issue 16, ``benchmarks/diag_pgm_updates.py``): on Example 1 the first
measurement of a pass after a gap of about a day slices a slab 1.5 arcsec (~3 km) thick out of
a cloud hundreds to thousands of km wide: about one particle in 10,000 lies in it (ESS ~1). The
conditioning then rests entirely on the Gaussian fitted to each cluster, and clusters that long
propagation has bent (Mardia kurtosis up to 2.3x the Gaussian value) put the conditional in the
wrong place: in single runs the truth's NEES rose from ~4-5 to ~11-15 across that one update.
The option ``split_components``: a Gaussian fitted to a smaller piece of a smoothly bent cloud
deviates from it by the curvature times the piece's size squared, so at a sharp measurement the
PGM may cluster into more, smaller components, each still large enough for a 6-D covariance
(the merge rule). Off by default: over 35 tuning seeds per IOD it did not keep custody more
often; the aggregate drift turned out to come from every update (component_spread.py).
Example 3 (150-day gap) ships with 40 components at sharp measurements: custody on seen seeds
3000-3029 went from 26/30 to 27/30 and its largest final error from 214,257 to 1,596 km; on
unseen seeds 3260-3289, 27/30 against 24/30 (core/scenarios/example-3.toml has the sweep).
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
