"""Quantiles of the chi-square distribution, without importing scipy.stats."""
from __future__ import annotations

__all__ = ["chi2_ppf"]


def chi2_ppf(q: float, dof: float) -> float:
    """Quantile of the chi-square distribution: 2 P^-1(dof/2, q) with P the regularised lower
    incomplete gamma function; the value ``scipy.stats.chi2.ppf`` returns, without importing
    scipy.stats (~0.7 s of CPU at the end of every run)."""
    from scipy.special import gammaincinv

    return float(2 * gammaincinv(dof / 2, q))
