"""Clusterer: particles -> labels."""
from __future__ import annotations

from abc import abstractmethod
from typing import ClassVar

import numpy as np

from cistrack.errors import FilterError
from cistrack.interfaces.component import Component

__all__ = ["Clusterer", "checked_labels"]


class Clusterer(Component):
    """Partition particles into components. Implementations standardise coordinates themselves."""

    kind = "clustering"
    chooses_n_components: ClassVar[bool] = False
    """Whether the clusterer decides how many clusters to return itself, its ``n_components``
    parameter (if any) only a hint: the conformance suite then does not hold it to at most
    ``n_components`` clusters (``max_components`` is always a bound)."""

    @abstractmethod
    def cluster(self, x: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Labels (N,) int in [0, M) for the particles ``x`` (N, d); every label in range is used.
        ``x`` may be read-only (the PGM hands a read-only view of its particles): never write into it."""


def checked_labels(labels, n: int, who: str) -> np.ndarray:
    """A clusterer's ``labels`` for ``n`` particles as a (n,) intp array, refused (FilterError naming
    ``who``) unless they are what :meth:`Clusterer.cluster` promises: n whole numbers from 0 to n - 1
    that use every value from 0 to their largest, M - 1 (whole-valued floats are taken as they are),
    as the conformance suite requires: labels {0, 2} had been renumbered silently (probe L10)."""
    try:
        raw = np.asarray(labels)
        values = raw.astype(float) if raw.dtype.kind in "biuf" else None
    except (TypeError, ValueError):
        values = None
    if values is None:
        raise FilterError(f"{who}: cluster() returned {_what(labels)}, not labels (a (N,) array of whole numbers)")
    if values.shape != (n,):
        raise FilterError(f"{who}: cluster() returned labels of shape {values.shape} for {n} particles; "
                          f"expected ({n},)")
    if n and not (np.all(np.isfinite(values)) and np.all(values == np.floor(values))
                  and values.min() >= 0 and values.max() < n):
        finite = values[np.isfinite(values)]  # (numpy warns "All-NaN slice" on nanmin of NaN alone)
        span = f"from {finite.min():g} to {finite.max():g}" if finite.size else "none of them finite"
        raise FilterError(f"{who}: cluster() returned labels that are not whole numbers from 0 to {n - 1} "
                          f"({span}{', some NaN or infinite' if 0 < finite.size < n else ''})")
    out = raw.astype(np.intp)
    unused = np.flatnonzero(np.bincount(out) == 0) if n else out[:0]
    if unused.size:
        raise FilterError(f"{who}: cluster() returned labels that leave {unused.size} of the values from 0 to "
                          f"{out.max()} unused (e.g. {unused[0]}); labels must use every value in [0, M), M the "
                          "number of clusters (renumber them without gaps)")
    return out


def _what(value) -> str:
    """``value`` as a message names what it is: ``None``, ``ndarray of <U1``, ``str``."""
    if value is None:
        return "None"
    dtype = getattr(value, "dtype", None)
    return type(value).__name__ + (f" of {dtype}" if dtype is not None else "")

