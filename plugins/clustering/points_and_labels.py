"""Standardised coordinates shared by the clusterers, and label bookkeeping."""
from __future__ import annotations

import numpy as np

from cistrack.errors import ParameterError

__all__ = ["standardize", "compact_labels", "check_points", "sklearn_seed", "n_distinct_at_least"]


def check_points(x: np.ndarray, owner: str) -> np.ndarray:
    """``x`` as a finite float array (N, d) with N >= 1; a clear error otherwise."""
    x = np.asarray(x, dtype=float)
    if x.ndim != 2 or x.shape[0] == 0:
        raise ParameterError(f"clustering '{owner}': expected points of shape (N, d) with N >= 1, got {x.shape}")
    if not np.all(np.isfinite(x)):
        raise ParameterError(f"clustering '{owner}': points contain NaN or infinity")
    return x


def standardize(x: np.ndarray) -> np.ndarray:
    """Each coordinate of ``x`` (N, d) shifted to zero mean and scaled to unit standard deviation.

    Coordinates with zero spread (all particles equal) are only shifted, so duplicates stay finite.
    """
    mean = x.mean(axis=0)
    std = x.std(axis=0)
    std[~(std > 0)] = 1.0
    return (x - mean) / std


def compact_labels(labels: np.ndarray) -> np.ndarray:
    """Relabel (N,) ints so the used labels are exactly 0..M-1 (empty clusters disappear)."""
    _, inv = np.unique(labels, return_inverse=True)
    return inv.reshape(-1).astype(np.intp)


def sklearn_seed(rng: np.random.Generator) -> int:
    """A scikit-learn ``random_state`` drawn from ``rng``."""
    return int(rng.integers(2**31 - 1))


def n_distinct_at_least(x: np.ndarray, k: int) -> int:
    """min(k, number of distinct rows of ``x``), computed cheaply when there are plenty."""
    if k <= 1:
        return k
    head = x[: max(4 * k, 64)]
    n = np.unique(head, axis=0).shape[0]
    if n >= k:
        return k
    return min(k, np.unique(x, axis=0).shape[0])
