"""The time series the viewer plots: log10 of errors and sigmas, NEES with its chi-square band,
the mixture weights ranked.

Errors and sigmas of a run span six decades (an IOD error of 10^5 km, a converged one of a few
km), so the panels plot their log10: every decade gets the same height. Pure numpy and plain
data; the recorder logs each entry as a scalar at ``series/<panel>/<name>``.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["NEES_BAND", "NEES_BAND_ENTITIES", "SERIES", "Series", "log10_series", "nees_band_series",
           "nees_y_range", "ranked_weights", "rank_entity"]

NEES_BAND = (1.6354, 12.5916)
"""5 % and 95 % points of chi-square with 6 degrees of freedom: 90 % of a consistent filter's
NEES values lie in this band."""


class Series:
    """One plotted line: entity ``series/<panel>/<name>``, legend ``label``, RGB ``color``,
    computed from a step's metrics as ``log10(metrics[metric] * factor)``."""

    def __init__(self, panel: str, name: str, label: str, color: tuple[int, int, int],
                 metric: str, factor: float = 1.0) -> None:
        self.panel, self.name, self.label, self.color = panel, name, label, color
        self.metric, self.factor = metric, factor

    @property
    def entity(self) -> str:
        return f"series/{self.panel}/{self.name}"


_ERROR, _X, _Y, _Z = (235, 70, 60), (90, 160, 255), (80, 200, 120), (240, 180, 50)
SERIES: tuple[Series, ...] = (
    Series("position", "error", "error", _ERROR, "pos_err_km"),
    Series("position", "sigma_x", "1-sigma x", _X, "sigma_x_km"),
    Series("position", "sigma_y", "1-sigma y", _Y, "sigma_y_km"),
    Series("position", "sigma_z", "1-sigma z", _Z, "sigma_z_km"),
    Series("velocity", "error", "error", _ERROR, "vel_err_ms"),
    Series("velocity", "sigma_vx", "1-sigma vx", _X, "sigma_vx_cms", 0.01),
    Series("velocity", "sigma_vy", "1-sigma vy", _Y, "sigma_vy_cms", 0.01),
    Series("velocity", "sigma_vz", "1-sigma vz", _Z, "sigma_vz_cms", 0.01),
    Series("nees", "nees", "NEES", (200, 120, 255), "nees"),
)
"""Position in log10 km, velocity in log10 m/s (the cm/s sigmas times 0.01), NEES in log10."""

NEES_BAND_ENTITIES = ("series/nees/band_5", "series/nees/band_95")


def log10_series(metrics: dict) -> dict[str, float]:
    """``{entity: log10 value}`` of every :data:`SERIES` entry whose metric is finite and > 0."""
    out = {}
    for s in SERIES:
        v = metrics.get(s.metric)
        if isinstance(v, (int, float, np.number)) and not isinstance(v, (bool, np.bool_)):
            x = float(v) * s.factor
            if math.isfinite(x) and x > 0.0:
                out[s.entity] = math.log10(x)
    return out


def nees_band_series() -> dict[str, float]:
    """The chi-square band's two edges in log10, logged beside every NEES value."""
    return {e: math.log10(b) for e, b in zip(NEES_BAND_ENTITIES, NEES_BAND)}


def nees_y_range() -> tuple[float, float]:
    """The NEES panel's y range, log10: a decade either side of the chi-square band."""
    lo, hi = (math.log10(b) for b in NEES_BAND)
    return lo - 1.0, hi + 1.0


def ranked_weights(weights: np.ndarray, n_ranks: int) -> np.ndarray:
    """Mixture weights (M,) sorted largest first and padded with zeros to ``n_ranks`` (>= M):
    component identities change from step to step, ranks do not."""
    w = np.sort(np.asarray(weights, dtype=float).reshape(-1))[::-1]
    out = np.zeros(max(int(n_ranks), w.size))
    out[:w.size] = w
    return out


def rank_entity(rank: int) -> str:
    """Entity of the ``rank``-th largest weight (1 = largest): ``components/ranked/<rank>``."""
    return f"components/ranked/{int(rank)}"
