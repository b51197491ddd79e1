"""Clusterer: particles -> labels."""
from __future__ import annotations

from abc import abstractmethod

import numpy as np

from cistrack.interfaces.component import Component

__all__ = ["Clusterer"]


class Clusterer(Component):
    """Partition particles into components. Implementations standardise coordinates themselves."""

    kind = "clustering"

    @abstractmethod
    def cluster(self, x: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Labels (N,) int in [0, M) for the particles ``x`` (N, d); every label in range is used."""
