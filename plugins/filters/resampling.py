"""Importance weights in the log domain, effective sample size and systematic resampling."""
from __future__ import annotations

import numpy as np

from cistrack.errors import FilterError
from cistrack.numerics.special_functions import logsumexp

__all__ = ["normalize_log_weights", "effective_sample_size", "systematic_resample"]


def normalize_log_weights(logw: np.ndarray, who: str) -> tuple[np.ndarray, float]:
    """Shift log weights (N,) so their exponentials sum to one.

    Returns (normalised log weights (N,), log of the original sum). Works when every weight
    underflows in the linear domain; raises FilterError if none is finite.
    """
    logw = np.asarray(logw, dtype=float)
    if np.any(np.isnan(logw)) or not np.any(np.isfinite(logw)):
        raise FilterError(f"filter '{who}': every weight is zero or NaN; the belief cannot continue")
    total = logsumexp(logw)
    return logw - total, total


def effective_sample_size(weights: np.ndarray) -> float:
    """1 / sum(w^2) of normalised weights (N,)."""
    w = np.asarray(weights, dtype=float)
    return float(1.0 / np.sum(w * w))


def systematic_resample(weights: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    """Indices (n,) drawn by systematic resampling from normalised ``weights`` (N,)."""
    c = np.cumsum(np.asarray(weights, dtype=float))
    c[-1] = 1.0
    u = (rng.random() + np.arange(n)) / n
    return np.minimum(np.searchsorted(c, u, side="right"), c.size - 1)
