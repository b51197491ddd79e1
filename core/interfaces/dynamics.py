"""Dynamics: equations of motion and ensemble propagation."""
from __future__ import annotations

from abc import abstractmethod
from dataclasses import dataclass
from typing import Any

import numpy as np

from cistrack.interfaces.component import Component

__all__ = ["Body", "Dynamics", "Propagation", "check_output_times"]


def check_output_times(label: str, t0: Any, times: Any) -> tuple[float, np.ndarray]:
    """``t0`` as a float and ``times`` as (K,) float64 (TU): numbers, finite, at least one,
    monotonic in one direction from ``t0``; a :class:`~cistrack.errors.StateError` naming ``label``
    (the model) otherwise."""
    from cistrack.errors import StateError

    try:
        t0 = float(t0)
        t_out = np.atleast_1d(np.asarray(times, dtype=np.float64)).reshape(-1)
    except (TypeError, ValueError) as exc:
        raise StateError(f"{label}: t0 and times must be numbers (TU): {exc}") from None
    if t_out.size == 0:
        raise StateError(f"{label}: no output times given")
    if not (np.isfinite(t0) and np.all(np.isfinite(t_out))):
        raise StateError(f"{label}: t0 and times must be finite")
    d = np.diff(np.concatenate(([t0], t_out)))
    if not (np.all(d >= 0) or np.all(d <= 0)):
        raise StateError(f"{label}: times must be monotonic in one direction from t0={t0}")
    return t0, t_out


@dataclass(frozen=True)
class Body:
    """A massive body of a dynamics model (a primary) and the sphere particles can hit.

    Attributes
    ----------
    name : str              e.g. "Earth"
    position : (3,) float   synodic position, LU (at t = 0 for a model whose bodies move; see
                            :meth:`position_at`)
    radius : float          impact radius, LU (0: no impact surface)
    mass_fraction : float   the body's mass over the system's (Earth 1 - mu, Moon mu in the
                            Earth-Moon CR3BP; 0 when the model does not say)
    """

    name: str
    position: np.ndarray
    radius: float
    mass_fraction: float = 0.0

    def position_at(self, t) -> np.ndarray:
        """Synodic position (3,) LU at time ``t`` (TU); constant here, a model with moving
        bodies returns Body subclasses that override this."""
        return np.asarray(self.position, dtype=float)


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
    steps : (N,) float or None
        Step size (TU) each particle's integrator proposes next, for models that can start a
        later call with it (:attr:`Dynamics.carries_steps`); None otherwise.
    """

    times: np.ndarray
    states: np.ndarray
    alive: np.ndarray
    impact_body: np.ndarray
    impact_time: np.ndarray
    steps: np.ndarray | None = None

    @property
    def final(self) -> np.ndarray:
        """States at the last output time, (N, 6)."""
        return self.states[-1]

    def impact_counts(self, bodies: tuple[Body, ...]) -> dict[str, int]:
        """Number of particles that hit each body, by name."""
        return {b.name: int(np.sum(self.impact_body == i)) for i, b in enumerate(bodies)}


class Dynamics(Component):
    """Equations of motion of one model and propagation of ``(N, 6)`` state arrays.

    States are nondimensional synodic (LU, VU), times TU. A model whose constructor has an
    ``epoch`` parameter (ISO-8601 UTC of t = 0; e.g. ``ephemeris``) is handed the scenario's.
    Implementations must propagate every
    particle with its own adaptive error control, report particles that hit a body through
    :class:`Propagation` instead of returning NaN, and support propagation backward in time.
    """

    kind = "dynamics"
    carries_steps: bool = False
    """True when :meth:`propagate` accepts ``steps=`` (each particle's first step size, (N,) TU)
    and returns :attr:`Propagation.steps`, so that filters can carry step sizes between calls
    (every :class:`~cistrack.propagation.CompiledDynamics` does)."""

    @property
    def primaries(self) -> tuple[Body, ...]:
        """The model's massive bodies with their mass fractions, positions and radii (e.g. the
        Earth and the Moon; :mod:`cistrack.astro.primaries` has the Earth-Moon values). Default: the
        impact bodies."""
        return self.bodies

    @property
    def bodies(self) -> tuple[Body, ...]:
        """Bodies whose surfaces stop a particle (empty if the model has none). Default: the
        primaries with a positive radius."""
        if type(self).primaries is Dynamics.primaries:
            return ()
        return tuple(b for b in self.primaries if b.radius > 0)

    def primary(self, name: str) -> Body | None:
        """The primary called ``name`` (case-insensitive), or None."""
        want = name.strip().lower()
        return next((b for b in self.primaries if b.name.lower() == want), None)

    @abstractmethod
    def derivatives(self, t: float, states: np.ndarray) -> np.ndarray:
        """Time derivative of ``states`` (N, 6) at time ``t`` (TU) -> (N, 6)."""

    @abstractmethod
    def propagate(self, states: np.ndarray, t0: float, times) -> Propagation:
        """Propagate ``states`` (N, 6) from ``t0`` to each of ``times`` (scalar or (K,) TU).

        ``times`` must be monotonic in one direction from ``t0`` (all later, or all earlier).
        """

    def propagate_with_stm(self, state: np.ndarray, t0: float, times) -> tuple[np.ndarray, np.ndarray]:
        """One ``state`` (6,) and its state transition matrix from ``t0`` to each of ``times``.

        Optional. Returns ``(states (K, 6), stms (K, 6, 6))`` with ``stms[k] = d states[k] / d state``
        (synodic LU, VU, times TU; ``times`` as for :meth:`propagate`: (K,) or scalar, monotonic
        in one direction from ``t0``). Used by the batch least-squares fit (:mod:`cistrack.fit`).
        The default differences :meth:`propagate` centrally
        (:func:`cistrack.interfaces.transition_matrix.stm_by_central_differences`); models with
        variational equations override it. Raises :class:`cistrack.errors.StateError` for
        malformed input and :class:`cistrack.errors.PropagationError` when the trajectory hits a
        body.
        """
        from cistrack.interfaces.transition_matrix import stm_by_central_differences

        return stm_by_central_differences(self, state, t0, times)

    sensitivity_parameters: tuple[str, ...] = ()
    """Solve-for parameters whose d x / d p :meth:`propagate_with_sensitivity` integrates (optional;
    none by default: the least squares then differences the others centrally)."""

    def propagate_with_sensitivity(self, state: np.ndarray, t0: float, times,
                                   name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """As :meth:`propagate_with_stm`, and d states[k] / d p (K, 6) of the solve-for parameter
        ``name`` (one of :attr:`sensitivity_parameters`; LU, VU per unit of the parameter), the
        state at ``t0`` held.

        Optional: a model whose variational equations carry a parameter's sensitivity overrides
        it and names the parameter in :attr:`sensitivity_parameters`; the batch least squares then
        takes that parameter's partials from it instead of two more propagations of the arc per
        iteration. The default refuses every name with :class:`cistrack.errors.StateError`.
        """
        from cistrack.errors import StateError

        raise StateError(f"{self._label()}: no integrated "
                         f"sensitivity of {name!r} (sensitivity_parameters is empty)")
