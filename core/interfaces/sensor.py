"""Sensor: measurement model, noise, residuals, visibility and simulation."""
from __future__ import annotations

import functools
from abc import abstractmethod

import numpy as np

from cistrack.interfaces.component import Component
from cistrack.model.measurement import MeasurementSet
from cistrack.interfaces.schedule import Pass

__all__ = ["Sensor", "passes_from_mask"]


def passes_from_mask(times: np.ndarray, mask: np.ndarray) -> list[Pass]:
    """The contiguous runs of True in ``mask`` (K,) as passes between the sample ``times`` (K,) TU."""
    out: list[Pass] = []
    k, n = 0, mask.shape[0]
    while k < n:
        if mask[k]:
            j = k
            while j + 1 < n and mask[j + 1]:
                j += 1
            out.append(Pass(float(times[k]), float(times[j])))
            k = j + 1
        else:
            k += 1
    return out


class Sensor(Component):
    """A sensor that observes states. Angles are radians, ranges LU, times TU.

    The scenario's UTC epoch is handed to every sensor whose constructor has an ``epoch``
    parameter (an ISO-8601 string); a scenario may not set it in the sensor table.
    """

    kind = "sensor"
    names: tuple[str, ...] = ()
    """Name of each measurement component, e.g. ("azimuth", "elevation", "range")."""
    angular: tuple[bool, ...] = ()
    """Whether each component is an angle that wraps at ±pi in residuals."""
    line_of_sight_tolerance_lu: float = 1e-9
    """How far ``observer_position(t) + range * line_of_sight(measure(x, t), t)`` may miss the
    true position of x, LU. Exact for geometric sensors; a sensor whose angles include light time
    sees the target where it was (it moved by its velocity times the light time) and declares
    that bound."""

    @abstractmethod
    def measure(self, states: np.ndarray, t) -> np.ndarray:
        """Noise-free measurement h(x): states (N, 6), t scalar or (N,) TU -> (N, m)."""

    @abstractmethod
    def sigmas(self, states: np.ndarray, t) -> np.ndarray:
        """One-sigma noise of each component for the true states (N, 6) -> (N, m)."""

    def noise_covariance(self, states: np.ndarray, t) -> np.ndarray:
        """Noise covariance R for the true states: (N, m, m), diagonal."""
        s = self.sigmas(states, t)
        return np.einsum("ni,ij->nij", s * s, np.eye(s.shape[1]))

    def residual(self, z: np.ndarray, zhat: np.ndarray) -> np.ndarray:
        """z - zhat (..., m) with angular components wrapped into [-pi, pi)."""
        r = np.asarray(z, dtype=float) - np.asarray(zhat, dtype=float)
        for i in _angular_columns(tuple(self.angular)):  # a column at a time: no boolean-mask copies
            r[..., i] = (r[..., i] + np.pi) % (2.0 * np.pi) - np.pi
        return r

    @abstractmethod
    def visible(self, states: np.ndarray, t) -> np.ndarray:
        """Whether each state (N, 6) can be observed at t (scalar or (N,)) -> (N,) bool."""

    @abstractmethod
    def observer_position(self, t) -> np.ndarray:
        """Observer position in the synodic frame, LU: t scalar -> (3,), t (K,) -> (K, 3)."""

    @abstractmethod
    def line_of_sight(self, angles: np.ndarray, t) -> np.ndarray:
        """Unit vectors (N, 3) in the synodic frame along measured angle pairs (N, 2) [rad] at t
        (scalar or (N,) TU). A target at range rho (LU) is at ``observer_position(t) + rho * los``;
        IOD methods use this to turn angles and a range into synodic positions."""

    def for_measurement(self, measurement) -> "Sensor":
        """The sensor that took ``measurement`` (a :class:`cistrack.model.measurement.Measurement`):
        itself, except for a sensor standing for several sites, which returns the one at
        ``measurement.site``. Filters measure predictions with it, so that two measurements at
        the same time from two sites are each predicted from their own site."""
        return self

    def inertial_frame(self):
        """The Earth-centred inertial frame the sensor's synodic frame is placed in, as a
        :class:`cistrack.astro.inertial_frame.InertialFrame` (used to export estimates), or None when
        the sensor has no such placement."""
        return None

    def passes(self, times: np.ndarray, states: np.ndarray) -> list[Pass]:
        """Visibility passes of a trajectory sampled at ``times`` (K,) with ``states`` (K, 6).

        The default takes contiguous runs of visible samples; sensors may refine the edges.
        """
        return passes_from_mask(times, np.asarray(self.visible(states, times), dtype=bool))

    @abstractmethod
    def simulate(self, states: np.ndarray, times: np.ndarray, rng: np.random.Generator) -> MeasurementSet:
        """Noisy measurements of a truth trajectory: states (K, 6) at times (K,) TU."""


@functools.lru_cache(maxsize=64)
def _angular_columns(angular: tuple) -> tuple[int, ...]:
    """Indices of the True entries of a sensor's ``angular`` flags."""
    return tuple(i for i, a in enumerate(angular) if bool(a))
