"""Standardised coordinates shared by the clusterers, and label bookkeeping."""
from __future__ import annotations

import numpy as np

from cistrack.errors import ParameterError
from cistrack.lazy import lazy_njit

__all__ = ["standardize", "Standardizer", "compact_labels", "check_points", "sklearn_seed", "n_distinct_at_least"]


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
    The result is bit for bit numpy's ``(x - x.mean(axis=0)) / x.std(axis=0)``: for a C-ordered
    ``x`` numpy sums along axis 0 row by row, and the compiled :func:`_column_moments` and
    :func:`_scale_rows` make the same additions in the same order with no temporaries (the PGM standardises 10,000
    particles at every update); other layouts go through numpy itself.
    """
    x = np.asarray(x, dtype=np.float64)
    if not x.flags.c_contiguous:  # numpy sums a contiguous axis pairwise: keep its numbers there
        mean = x.mean(axis=0)
        std = x.std(axis=0)
        std[~(std > 0)] = 1.0
        return (x - mean) / std
    d = x.shape[1]
    mean, std, out = np.zeros(d), np.empty(d), np.empty_like(x)
    _column_moments(x, mean, std)
    _scale_rows(x, mean, std, out)
    return out


class Standardizer:
    """:func:`standardize` of ``x`` (N, d) one block of rows at a time: ``rows(a, b)`` equals
    ``standardize(x)[a:b]`` bit for bit, without an (N, d) copy of the points (C-ordered float64
    ``x``; other layouts are standardised whole, once)."""

    def __init__(self, x: np.ndarray):
        x = np.asarray(x, dtype=np.float64)
        self._z = None if x.flags.c_contiguous else standardize(x)
        self._x = x
        if self._z is None:
            self._mean, self._std = np.zeros(x.shape[1]), np.empty(x.shape[1])
            _column_moments(x, self._mean, self._std)

    def __len__(self) -> int:
        return self._x.shape[0]

    def rows(self, a: int, b: int) -> np.ndarray:
        """Standardised rows a:b, (b - a, d)."""
        if self._z is not None:
            return self._z[a:b]
        out = np.empty((max(0, min(b, len(self)) - a), self._x.shape[1]))
        _scale_rows(self._x[a:b], self._mean, self._std, out)
        return out

    def take(self, idx: np.ndarray) -> np.ndarray:
        """Standardised rows ``idx`` (n,), (n, d)."""
        if self._z is not None:
            return self._z[idx]
        out = np.empty((idx.size, self._x.shape[1]))
        _scale_rows(self._x[idx], self._mean, self._std, out)
        return out


@lazy_njit(cache=True)
def _column_moments(x, mean, std):
    """mean (d,) and std (d,) of the columns of x (N, d), as :func:`standardize` computes them."""
    n, d = x.shape
    for i in range(n):
        for a in range(d):
            mean[a] += x[i, a]
    for a in range(d):
        mean[a] = mean[a] / n
    var = np.zeros(d)
    for i in range(n):
        for a in range(d):
            t = x[i, a] - mean[a]
            var[a] += t * t
    for a in range(d):
        s = np.sqrt(var[a] / n)
        std[a] = s if s > 0 else 1.0


@lazy_njit(cache=True)
def _scale_rows(x, mean, std, out):
    """out (n, d) = (x - mean) / std, row by row, as :func:`standardize` writes it."""
    n, d = x.shape
    for i in range(n):
        for a in range(d):
            out[i, a] = (x[i, a] - mean[a]) / std[a]


def compact_labels(labels: np.ndarray) -> np.ndarray:
    """Relabel (N,) ints so the used labels are exactly 0..M-1 (empty clusters disappear), in the
    order of the old labels: ``np.unique(labels, return_inverse=True)[1]``, without its sort."""
    labels = np.asarray(labels).reshape(-1)
    if labels.size == 0 or labels.min() < 0:
        _, inv = np.unique(labels, return_inverse=True)
        return inv.reshape(-1).astype(np.intp)
    rank = np.cumsum(np.bincount(labels) > 0) - 1
    return rank[labels].astype(np.intp, copy=False)


def sklearn_seed(rng: np.random.Generator) -> int:
    """A scikit-learn ``random_state`` drawn from ``rng``."""
    return int(rng.integers(2**31 - 1))


def n_distinct_at_least(x: np.ndarray, k: int) -> int:
    """min(k, number of distinct rows of ``x``), computed cheaply when there are plenty."""
    if k <= 1:
        return k
    head = x[: max(4 * k, 64)]
    if np.unique(head[:, 0]).size >= k:  # rows that differ in one coordinate are distinct (10x cheaper)
        return k
    n = np.unique(head, axis=0).shape[0]
    if n >= k:
        return k
    return min(k, np.unique(x, axis=0).shape[0])
