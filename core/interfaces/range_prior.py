"""RangePrior: how a kinematic-fit IOD draws the unknown range of each sampled measurement."""
from __future__ import annotations

from abc import abstractmethod
from typing import ClassVar

import numpy as np

from cistrack.interfaces.component import Component

__all__ = ["RangePrior"]


class RangePrior(Component):
    """A distribution of the observer-to-target range, a parameter of a kinematic-fit IOD.

    ``needs_measured_range`` says whether :meth:`draw` uses the measured ranges (then the
    measurements must carry a 'range' component).
    """

    kind = "range-prior"
    needs_measured_range: ClassVar[bool] = False

    @abstractmethod
    def draw(self, measured_lu: np.ndarray | None, shape: tuple[int, int],
             rng: np.random.Generator) -> np.ndarray:
        """Ranges (LU) of ``shape``: (n, K) one per sample and measurement, or (n, 1) one per
        sample. ``measured_lu`` (K,) LU: the measured ranges (None unless needs_measured_range).
        The result broadcasts to (n, K)."""
