"""Quantiles of the chi-square distribution, without importing scipy."""
from __future__ import annotations

from cistrack.numerics.special_functions import chi2_ppf

__all__ = ["chi2_ppf"]
