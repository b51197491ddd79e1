"""A linear-Gaussian test problem built on the real interfaces: a force-free particle (exactly
linear dynamics) observed through a fixed linear map (no angles), so that least squares has a
closed form to compare with."""
from __future__ import annotations

import numpy as np

from cistrack.interfaces.dynamics import Dynamics, Propagation
from cistrack.interfaces.sensor import Sensor
from cistrack.model.measurement import MeasurementSet

__all__ = ["FreeParticle", "LinearSensor", "PositionSensor", "free_particle_stm", "burned_free_particle"]


def free_particle_stm(dt: float) -> np.ndarray:
    """Transition matrix (6, 6) of x'' = 0 over dt."""
    phi = np.eye(6)
    phi[:3, 3:] = dt * np.eye(3)
    return phi


class FreeParticle(Dynamics):
    """x'' = 0: positions move with constant velocity (exact propagation, no bodies)."""

    def derivatives(self, t, states):
        s = np.atleast_2d(np.asarray(states, dtype=float))
        return np.concatenate([s[:, 3:], np.zeros_like(s[:, 3:])], axis=1)

    def propagate(self, states, t0, times):
        s = np.atleast_2d(np.asarray(states, dtype=float))
        tt = np.atleast_1d(np.asarray(times, dtype=float))
        out = np.stack([s @ free_particle_stm(t - t0).T for t in tt])
        n = s.shape[0]
        return Propagation(tt, out, np.ones(n, bool), np.full(n, -1), np.full(n, np.inf))


class LinearSensor(Sensor):
    """z = M x + noise with a fixed (3, 6) matrix M and one-sigma ``sigma`` per component."""

    names = ("u", "v", "w")
    angular = (False, False, False)

    def __init__(self, seed: int = 7, sigma: float = 1e-6):
        self.seed = seed
        self.sigma = sigma
        self.matrix = np.random.default_rng(seed).standard_normal((3, 6))

    def measure(self, states, t):
        return np.atleast_2d(np.asarray(states, dtype=float)) @ self.matrix.T

    def sigmas(self, states, t):
        return np.full((np.atleast_2d(states).shape[0], 3), self.sigma)

    def visible(self, states, t):
        return np.ones(np.atleast_2d(states).shape[0], dtype=bool)

    def observer_position(self, t):
        return np.zeros(3) if np.ndim(t) == 0 else np.zeros((len(t), 3))

    def line_of_sight(self, angles, t):
        raise NotImplementedError("a linear sensor measures no angles")

    def simulate(self, states, times, rng):
        z = self.measure(states, times)
        return MeasurementSet(times, z + self.sigma * rng.standard_normal(z.shape), self.sigmas(states, times),
                              self.names)


class PositionSensor(LinearSensor):
    """z = position + noise: the three position components of the state."""

    def __init__(self, sigma: float = 1e-6):
        super().__init__(sigma=sigma)
        self.matrix = np.hstack([np.eye(3), np.zeros((3, 3))])


def burned_free_particle(x0: np.ndarray, dv: np.ndarray, tb: float, t: float) -> np.ndarray:
    """The state (6,) at ``t`` of a free particle from ``x0`` at 0 that changed its velocity by ``dv``
    at ``tb``."""
    x = x0 @ free_particle_stm(t).T
    return x + np.concatenate([dv * (t - tb), dv]) if t > tb else x
