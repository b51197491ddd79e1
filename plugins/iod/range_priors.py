"""The range priors of the kinematic-fit IOD (kind "range-prior"): the paper's two range models.

``noisy``
    rho ~ N(rho_meas, (alpha rho_meas)^2) around the *measured* range (the measurements need a
    'range' component; OD later ignores it).
``uniform``
    rho ~ U[range_min_km, range_max_km] (default 84,328-550,000 km, the cislunar bounds).
"""
from __future__ import annotations

import numpy as np

from cistrack.interfaces.component import check_positive, check_range
from cistrack.api import hookimpl
from cistrack.interfaces import RangePrior
from cistrack.units import km_to_lu

__all__ = ["NoisyRange", "UniformRange"]


class NoisyRange(RangePrior):
    """Gaussian ranges around the measured range, 1-sigma = alpha x measured range.

    Parameters
    ----------
    alpha : float
        Relative 1-sigma of the measured range (0.05: 5 % of the range).
    """

    needs_measured_range = True

    def __init__(self, alpha: float = 0.05) -> None:
        self.alpha = check_range(self, "alpha", alpha, 0.0, 1.0, lo_open=True)

    def draw(self, measured_lu, shape, rng):
        """rho = rho_meas (1 + alpha N(0, 1)), LU, broadcasting ``shape`` against (K,)."""
        return np.asarray(measured_lu)[None] * (1.0 + self.alpha * rng.standard_normal(shape))


class UniformRange(RangePrior):
    """Ranges drawn uniformly between two bounds.

    Parameters
    ----------
    range_min_km : float
        Smallest range drawn, km (default 84,328 km: the cislunar lower bound).
    range_max_km : float
        Largest range drawn, km (default 550,000 km: the cislunar upper bound).
    """

    def __init__(self, range_min_km: float = 84_328.0, range_max_km: float = 550_000.0) -> None:
        self.range_min_km = check_positive(self, "range_min_km", range_min_km)
        self.range_max_km = check_positive(self, "range_max_km", range_max_km)
        if self.range_max_km <= self.range_min_km:
            self._fail("range_max_km", range_max_km, f"must exceed range_min_km ({range_min_km})")

    def draw(self, measured_lu, shape, rng):
        """rho ~ U[range_min, range_max] in LU, of ``shape``."""
        lo, hi = float(km_to_lu(self.range_min_km)), float(km_to_lu(self.range_max_km))
        return rng.uniform(lo, hi, size=shape)


@hookimpl
def cistrack_register(registry) -> None:
    registry.add("range-prior", "noisy", NoisyRange)
    registry.add("range-prior", "uniform", UniformRange)
