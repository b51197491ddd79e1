"""A small, plain-numpy Earth–Moon CR3BP used as a fixture by the conformance suite.

It is not registered as a plugin: it exists so that filter and IOD checks do not depend on the
correctness (or the compile time) of any other plugin.
"""
from __future__ import annotations

import numpy as np

from cistrack.interfaces.component import Component, check_positive
from cistrack.errors import ParameterError
from cistrack.interfaces.dynamics import Body, Dynamics, Propagation
from cistrack.astro.primaries import EARTH_RADIUS_KM, MOON_RADIUS_KM, MU_EARTH_MOON
from cistrack.units import LU_KM
from cistrack.testing.adaptive_rk import propagate_adaptive

__all__ = ["MU_EARTH_MOON", "ReferenceCR3BP", "cr3bp_derivatives", "as_states"]



def as_states(owner: Component, states: np.ndarray, name: str = "states") -> np.ndarray:
    """``states`` as a float (N, 6) array, or a ParameterError naming the argument."""
    x = np.asarray(states, dtype=float)
    if x.ndim == 1:
        x = x[None, :]
    if x.ndim != 2 or x.shape[1] != 6:
        raise ParameterError(f"{owner._label()}: {name} must have shape (N, 6), got {np.shape(states)}")
    if not np.all(np.isfinite(x)):
        raise ParameterError(f"{owner._label()}: {name} contain NaN or infinity")
    return x


def cr3bp_derivatives(states: np.ndarray, mu: float) -> np.ndarray:
    """CR3BP equations of motion: states (N, 6) LU, VU -> derivatives (N, 6) VU, VU/TU."""
    x, y, z = states[:, 0], states[:, 1], states[:, 2]
    vx, vy = states[:, 3], states[:, 4]
    r1 = np.sqrt((x + mu) ** 2 + y * y + z * z)
    r2 = np.sqrt((x - 1.0 + mu) ** 2 + y * y + z * z)
    g1 = (1.0 - mu) / r1**3
    g2 = mu / r2**3
    out = np.empty_like(states)
    out[:, :3] = states[:, 3:]
    out[:, 3] = x + 2.0 * vy - g1 * (x + mu) - g2 * (x - 1.0 + mu)
    out[:, 4] = y - 2.0 * vx - g1 * y - g2 * y
    out[:, 5] = -g1 * z - g2 * z
    return out


class ReferenceCR3BP(Dynamics):
    """Earth–Moon CR3BP with per-particle adaptive Dormand–Prince steps (testing fixture).

    Parameters
    ----------
    mu : float
        Mass ratio (dimensionless).
    rtol : float
        Relative tolerance of each particle's step control.
    """

    def __init__(self, mu: float = MU_EARTH_MOON, rtol: float = 1e-10):
        self.mu = check_positive(self, "mu", mu)
        self.rtol = check_positive(self, "rtol", rtol)

    @property
    def primaries(self) -> tuple[Body, ...]:
        return (Body("Earth", np.array([-self.mu, 0.0, 0.0]), EARTH_RADIUS_KM / LU_KM, 1.0 - self.mu),
                Body("Moon", np.array([1.0 - self.mu, 0.0, 0.0]), MOON_RADIUS_KM / LU_KM, self.mu))

    def derivatives(self, t: float, states: np.ndarray) -> np.ndarray:
        """Time derivative of ``states`` (N, 6) -> (N, 6); the model is autonomous."""
        return cr3bp_derivatives(as_states(self, states), self.mu)

    def _impact(self, y: np.ndarray) -> np.ndarray:
        hit = np.full(y.shape[0], -1, dtype=int)
        for i, b in enumerate(self.bodies):
            inside = np.sum((y[:, :3] - b.position) ** 2, axis=1) < b.radius**2
            hit = np.where((hit < 0) & inside, i, hit)
        return hit

    def propagate(self, states: np.ndarray, t0: float, times) -> Propagation:
        """Propagate ``states`` (N, 6) from ``t0`` to ``times`` (scalar or (K,), TU)."""
        x = as_states(self, states)
        ts = np.atleast_1d(np.asarray(times, dtype=float))
        if ts.ndim != 1 or not np.all(np.isfinite(ts)):
            raise ParameterError(f"{self._label()}: times must be a finite scalar or (K,) array")
        d = np.diff(np.concatenate([[float(t0)], ts]))
        if not (np.all(d >= 0) or np.all(d <= 0)):
            raise ParameterError(f"{self._label()}: times must be monotonic in one direction from t0")
        mu = self.mu
        out, alive, body, t_hit = propagate_adaptive(
            lambda t, y: cr3bp_derivatives(y, mu), x, float(t0), ts, rtol=self.rtol,
            atol=self.rtol * 1e-2, impact=self._impact)
        return Propagation(ts, out, alive, body, t_hit)
