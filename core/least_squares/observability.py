"""How well an arc determines the state: condition number and weakest direction.

The normal matrix N (6x6, information in LU, VU) is scaled to unit diagonal, Ns = D^-1 N D^-1
with D = sqrt(diag N), which makes its condition number independent of the units of each
coordinate (km or LU, km/s or VU). The weakest direction is the eigenvector v of Ns with the
smallest eigenvalue lambda, mapped back as the one-sigma displacement dx = D^-1 v / sqrt(lambda)
(dx^T N dx = 1): how far the state can move along it at one sigma, reported in km and km/s.
"""
from __future__ import annotations

import numpy as np

from cistrack.units import LU_KM, VU_KMS

__all__ = ["Observability", "observability", "to_km", "km_apart", "condition_text"]

_KM = np.array([LU_KM] * 3 + [VU_KMS] * 3)


def to_km(x: np.ndarray) -> np.ndarray:
    """A state or displacement (..., 6) in LU, VU -> km, km/s."""
    return np.asarray(x, dtype=float) * _KM


class Observability:
    """condition : float             condition number of the unit-diagonal normal matrix
    weakest_direction_km : (6,) float   one-sigma displacement along the weakest direction, km, km/s
    eigenvalues : (6,) float            eigenvalues of the scaled normal matrix, increasing"""

    def __init__(self, condition: float, weakest_direction_km: np.ndarray, eigenvalues: np.ndarray) -> None:
        self.condition = condition
        self.weakest_direction_km = weakest_direction_km
        self.eigenvalues = eigenvalues


def condition_text(condition: float) -> str:
    """"condition number 6.47e+03" (dimensionless), or in words when it is not finite: "singular
    (no finite condition number)"; never "inf" or "nan"."""
    c = float(condition)
    return f"condition number {c:.3g}" if np.isfinite(c) else "singular (no finite condition number)"


def km_apart(a: np.ndarray, b: np.ndarray) -> float:
    """Distance (km) between the positions of two states (6,) [LU, VU]."""
    return float(np.linalg.norm(to_km(np.asarray(a) - np.asarray(b))[:3]))


def observability(normal: np.ndarray) -> Observability:
    """:class:`Observability` of a symmetric normal matrix (6, 6); a non-positive eigenvalue gives
    an infinite condition number and the direction scaled to unit length (no sigma)."""
    n = 0.5 * (normal + normal.T)
    diag = np.diag(n)
    d = np.where(diag > 0, np.sqrt(np.abs(diag)), 1.0)     # 1 where a coordinate has no information
    ns = n / np.outer(d, d)
    w, v = np.linalg.eigh(ns)
    lam = float(w[0])
    u = v[:, 0] / d
    if lam > 0:
        cond = float(w[-1] / lam)
        dx = to_km(u / np.sqrt(lam))
    else:  # singular: the direction only (unit length in km, km/s), no one-sigma size
        cond = float("inf")
        dx = to_km(u)
        dx = dx / np.linalg.norm(dx)
    if dx[int(np.argmax(np.abs(dx)))] < 0:
        dx = -dx
    return Observability(cond, dx, w)
