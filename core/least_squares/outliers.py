"""Chi-square outlier rejection that can readmit observations.

After each converged pass of the fit, every observation (used or rejected) is tested with its
chi-square against the current orbit: above the threshold it is rejected, at or below it is
(re)admitted. The threshold for an observation of m components is the chi-square quantile with
m degrees of freedom at the probability of a ``sigma``-sigma Gaussian event (3 sigma, m = 2:
11.83). With ``robust`` on, the threshold is multiplied by max(1, s^2), s^2 the median of the
used observations' chi-square over its median under the noise model: while the orbit is still
poor (or the stated noise is too small), only the gross outliers go, not most of the data.
At most ``max_fraction`` of the observations is rejected (the worst ones).
"""
from __future__ import annotations

import math

import numpy as np

from cistrack.least_squares.chi_square import chi2_ppf

__all__ = ["rejection_threshold", "update_rejections"]


def rejection_threshold(sigma: float, dof: int) -> float:
    """Chi-square (dof degrees of freedom) exceeded with the probability of a |z| > sigma Gaussian
    event: 11.83 for sigma 3, dof 2."""
    return chi2_ppf(math.erf(sigma / math.sqrt(2.0)), dof)


def update_rejections(chi2: np.ndarray, dof: int, rejected: np.ndarray, sigma: float = 3.0,
                      robust: bool = True, max_fraction: float = 0.5) -> tuple[np.ndarray, float]:
    """New rejected flags (K,) and the threshold used, from each observation's chi-square (K,).

    ``rejected`` (K,) are the current flags (the robust scale is taken over the others)."""
    chi2 = np.asarray(chi2, dtype=float)
    thr = rejection_threshold(sigma, dof)
    if robust:
        used = chi2[~rejected] if np.any(~rejected) else chi2
        scale = float(np.median(used)) / chi2_ppf(0.5, dof)
        thr *= max(1.0, scale)
    new = chi2 > thr
    cap = int(math.floor(max_fraction * chi2.size))
    if int(new.sum()) > cap:
        worst = np.argsort(chi2)[::-1][:cap]
        new = np.zeros_like(new)
        new[worst] = True
    return new, thr
