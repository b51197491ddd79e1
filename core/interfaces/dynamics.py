"""Dynamics: equations of motion and ensemble propagation."""
from __future__ import annotations

from abc import abstractmethod
from dataclasses import dataclass

import numpy as np

from ..component import Component

__all__ = ["Body", "Dynamics", "Propagation"]


@dataclass(frozen=True)
class Body:
    """A massive body that particles can hit.

    Attributes
    ----------
    name : str            e.g. "Earth"
    position : (3,) float synodic position, LU (fixed in the rotating frame)
    radius : float        impact radius, LU
    """

    name: str
    position: np.ndarray
    radius: float


@dataclass
class Propagation:
    """Result of propagating an ensemble.

    Attributes
    ----------
    times : (K,) float
        Output times, TU since the scenario epoch.
    states : (K, N, 6) float
        States at each output time. A particle that hit a body keeps its state at impact for
        all later output times (never NaN); ``alive`` tells it apart.
    alive : (N,) bool
        False for particles that hit a body at or before the last output time.
    impact_body : (N,) int
        Index into ``Dynamics.bodies`` of the body hit, -1 for none.
    impact_time : (N,) float
        TU of the impact; +inf for particles that did not hit anything.
    """

    times: np.ndarray
    states: np.ndarray
    alive: np.ndarray
    impact_body: np.ndarray
    impact_time: np.ndarray

    @property
    def final(self) -> np.ndarray:
        """States at the last output time, (N, 6)."""
        return self.states[-1]

    def impact_counts(self, bodies: tuple[Body, ...]) -> dict[str, int]:
        """Number of particles that hit each body, by name."""
        return {b.name: int(np.sum(self.impact_body == i)) for i, b in enumerate(bodies)}


class Dynamics(Component):
    """Equations of motion of one model and propagation of ``(N, 6)`` state arrays.

    States are nondimensional synodic (LU, VU), times TU. Implementations must propagate every
    particle with its own adaptive error control, report particles that hit a body through
    :class:`Propagation` instead of returning NaN, and support propagation backward in time.
    """

    kind = "dynamics"

    @property
    def bodies(self) -> tuple[Body, ...]:
        """Bodies whose surfaces stop a particle (empty if the model has none)."""
        return ()

    @abstractmethod
    def derivatives(self, t: float, states: np.ndarray) -> np.ndarray:
        """Time derivative of ``states`` (N, 6) at time ``t`` (TU) -> (N, 6)."""

    @abstractmethod
    def propagate(self, states: np.ndarray, t0: float, times) -> Propagation:
        """Propagate ``states`` (N, 6) from ``t0`` to each of ``times`` (scalar or (K,) TU).

        ``times`` must be monotonic in one direction from ``t0`` (all later, or all earlier).
        """
